"""Measured orthogonal cuts that the FE and Oxley are compared with, as read here (README, "Validation against
experiments"), with where each value was read. Only values read as text are kept; none is estimated.

``AISI1045``: the eight AISI 1045 cuts (V = 200 and 400 m/min, h = 0.15 and 0.30 mm, rake -7 and +5 deg,
b = 1.6 mm) whose measured cutting and thrust forces Lalwani, Mehta and Jain (J. Mater. Process. Technol. 209
(2009) 5305) compare their Oxley model with, as transcribed in the public repository
``qingfengxia/quasi_static_metal_cutting`` (``validation.csv`` at commit 98b37712; the code of Xia and
Gillespie, J. Mater. Process. Technol. 2019, 116389): its columns ``F_c_exp`` and ``F_t_exp`` beside the model's
(its model columns of case 1, 576 N, 364 N, 0.43 mm, 942 C, are the published Oxley case of issue 17). The file
names no source for the measured columns and holds no measured chip thickness (its ``chip_thickness`` is the
model's); they appear to be the NIST tests (Ivester et al., Mach. Sci. Technol. 4 (2000) 511) that Lalwani et
al. compare with, not checked against either paper here.

``TI6AL4V``: the three dry cuts of Ti6Al4V at V = 60 m/min and h = 0.1 mm of Klippel et al. (Int. J. Adv. Manuf.
Technol. 135 (2024) 2871; tests V0438-V0440) as transcribed in ``alexsouza1989/ToolWearPredictor-LIME-SHAP``
(``ti_dataset.csv`` at 2e3ed29): forces per test, the measured edge radius 37-40 um and one chip thickness;
width and rake not in the readable text, so only the ratios F_f / F_c and h'/h are compared.
"""

from __future__ import annotations

from dataclasses import dataclass

AISI1045_SOURCE = ("Lalwani et al. 2009's experimental columns, "
                   "qingfengxia/quasi_static_metal_cutting validation.csv @ 98b37712")
TI6AL4V_SOURCE = ("Klippel et al. 2024, tests V0438-V0440, "
                  "alexsouza1989/ToolWearPredictor-LIME-SHAP ti_dataset.csv @ 2e3ed29")


@dataclass(frozen=True)
class Cut:
    """One measured orthogonal cut: speed [m/min], uncut chip thickness [mm], rake [deg], width [mm] (None: not
    read), forces [N] (totals over the width), chip thickness [mm] (None: not measured or not read)."""
    V: float
    h: float
    rake: float
    width: float | None
    Fc: float
    Ft: float
    chip: float | None = None


AISI1045 = (Cut(200, 0.15, -7, 1.6, 610, 450), Cut(200, 0.15, 5, 1.6, 585, 385),
            Cut(200, 0.30, -7, 1.6, 1150, 600), Cut(200, 0.30, 5, 1.6, 920, 450),
            Cut(400, 0.15, -7, 1.6, 600, 405), Cut(400, 0.15, 5, 1.6, 580, 280),
            Cut(400, 0.30, -7, 1.6, 1010, 605), Cut(400, 0.30, 5, 1.6, 980, 570))

AISI1045_MODEL = ((576, 364, 0.43), (433, 171, 0.31), (1007, 533, 0.72), (773, 233, 0.54),
                  (533, 302, 0.38), (406, 136, 0.28), (1041, 550, 0.79), (899, 366, 0.69))
"""The same file's Oxley model at each cut of :data:`AISI1045` (its ``F_cutting``, ``F_thrush``,
``chip_thickness``: N, N, mm): another implementation of the model wendel's is compared with cut by cut."""

TI6AL4V = (Cut(60, 0.1, 0, None, 211.8, 136.2), Cut(60, 0.1, 0, None, 212.3, 140.0),
           Cut(60, 0.1, 0, None, 214.3, 145.3, 0.1173))
"""Rake 0 is the scene's, assumed (not read)."""


MEASURED = {"steel": (AISI1045, AISI1045_SOURCE), "titanium": (TI6AL4V, TI6AL4V_SOURCE)}
"""The measured cuts and their provenance by material (:func:`reference`)."""


def matching(cuts, V: float, h: float, rake: float) -> list[Cut]:
    """The cuts at speed ``V`` [m/min], uncut chip thickness ``h`` [mm] and rake ``rake`` [deg] (to 1e-6).

    >>> [c.Fc for c in matching(AISI1045, 200.0, 0.15, -7.0)]
    [610]
    >>> matching(AISI1045, 300.0, 0.15, -7.0)
    []
    """
    return [c for c in cuts if abs(c.V - V) < 1e-6 * V and abs(c.h - h) < 1e-6 * h and abs(c.rake - rake) < 1e-6]


def reference(material: str, V: float, h: float, rake: float) -> dict | None:
    """The measured F_c, F_t [N] (means over the matching cuts), F_t / F_c and h'/h (None where not measured) for
    the scene's conditions; None where no cut matches. ``material``: "steel" or "titanium".

    >>> r = reference("titanium", 60.0, 0.1, 0.0)
    >>> round(r["Fc_N"], 1), round(r["Ft_N"], 1), round(r["Ft_over_Fc"], 2), round(r["h_ratio"], 2)
    (212.8, 140.5, 0.66, 1.17)
    >>> reference("steel", 200.0, 0.15, -7.0)["h_ratio"] is None
    True
    """
    table, source = MEASURED[material]
    cuts = matching(table, V, h, rake)
    if not cuts:
        return None
    fc, ft = sum(c.Fc for c in cuts) / len(cuts), sum(c.Ft for c in cuts) / len(cuts)
    chips = [c.chip for c in cuts if c.chip is not None]
    return {"Fc_N": fc, "Ft_N": ft, "Ft_over_Fc": ft / fc, "h_ratio": sum(chips) / len(chips) / h if chips else None,
            "width_mm": cuts[0].width, "source": source}
