"""A campaign of Oxley predictions over speed, uncut chip thickness and rake, and its Kienzle fits.

Each point takes milliseconds, so the campaign is one table (no run folders). The rows have the keys
the Kienzle fit reads (``h``, ``b``, ``Fc`` in m, m, N), so an FE campaign's rows fit the same way
(:func:`wendel.cutting.kienzle.fit_groups`).

Catalogue values beside the fits (specific cutting force for a 1 mm x 1 mm chip, by VDI 3323 material
group; ISCAR turning catalogue 2017 p. 558 and ISCAR boring catalogue 2022 p. 111, as reproduced at
docs.steelcam.org/iscar):

>>> CATALOGUE["aisi1045"][0]["kc11_N_per_mm2"], CATALOGUE["aisi1045"][0]["mc"]
(1500.0, 0.22)
"""

from __future__ import annotations

import itertools

from . import kienzle, oxley
from .scene import inputs

CATALOGUE = {
    "aisi1045": [
        {"source": "ISCAR 2017/2022, VDI 3323 group 2: non-alloy steel >= 0.25 % C, annealed (650 N/mm^2)",
         "kc11_N_per_mm2": 1500.0, "mc": 0.22},
        {"source": "ISCAR 2017/2022, VDI 3323 group 3: non-alloy steel < 0.55 % C, quenched and tempered "
                   "(850 N/mm^2)", "kc11_N_per_mm2": 1675.0, "mc": 0.24},
    ],
    "ti6al4v": [
        {"source": "ISCAR turning 2017, group 37: titanium alpha+beta alloys, Rm 1050 N/mm^2",
         "kc11_N_per_mm2": 2110.0, "mc": 0.22},
        {"source": "ISCAR boring 2022, group 37: titanium alpha+beta alloys, Rm 1050 N/mm^2",
         "kc11_N_per_mm2": 1245.0, "mc": 0.24},
    ],
}
"""Catalogue Kienzle constants by material key (the two ISCAR catalogues disagree for titanium)."""


def run(scene, speeds_m_per_min, uncuts_mm, rakes_deg) -> list[dict]:
    """Oxley at every (speed, uncut chip thickness, rake); a point without a solution is kept with its
    message and no forces."""
    rows = []
    for v, h, rake in itertools.product(speeds_m_per_min, uncuts_mm, rakes_deg):
        mat, th, cut, opt = inputs(scene, speed=v / 60.0, uncut=h * 1e-3, rake=rake)
        row = {"speed_m_per_min": v, "rake_deg": rake, "h": h * 1e-3, "b": cut.width}
        try:
            r = oxley.predict(mat, th, cut, opt)
        except oxley.OxleyError as exc:
            rows.append({**row, "status": f"no solution: {exc}"})
            continue
        rows.append({**row, "status": "ok", "Fc": r.Fc, "Ft": r.Ft, "chip_ratio": r.chip_ratio,
                     "T_int_C": r.T_int - 273.15, "phi_deg": r.phi * 57.29577951308232,
                     "ms": r.seconds * 1e3})
    return rows


def fits(rows: list[dict]) -> list[dict]:
    """Kienzle's k_c1.1 and m_c for each (speed, rake) and for each rake over all speeds."""
    ok = [r for r in rows if r["status"] == "ok"]
    out = []
    for (v, rake), f in kienzle.fit_groups(ok, by=("speed_m_per_min", "rake_deg")).items():
        out.append({"speed_m_per_min": v, "rake_deg": rake, **f.as_dict()})
    for (rake,), f in kienzle.fit_groups(ok, by=("rake_deg",)).items():
        out.append({"speed_m_per_min": "all", "rake_deg": rake, **f.as_dict()})
    return out
