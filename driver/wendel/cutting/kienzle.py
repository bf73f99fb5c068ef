"""Kienzle's cutting force law ``F_c = b k_c1.1 h^(1 - m_c)`` fitted to rows of F_c(h).

``k_c1.1`` is the specific cutting force at h = b = 1 mm [N/mm^2] and ``m_c`` the exponent by which the
specific cutting force ``k_c = F_c / (b h) = k_c1.1 h^-m_c`` falls with the uncut chip thickness h [mm]
(O. Kienzle, VDI-Z 94 (1952) 299-305). The fit is linear least squares in
``ln(F_c / b) = ln(k_c1.1) + (1 - m_c) ln(h)``; it takes rows from any source (the Oxley model, an FE
campaign, experiments), so the same function serves them all.

>>> rows = [{"h": h * 1e-3, "b": 1e-3, "Fc": 1700 * h ** 0.75} for h in (0.05, 0.1, 0.2, 0.4)]
>>> f = fit(rows)
>>> round(f.kc11 / 1e6, 6), round(f.mc, 6), f.n
(1700.0, 0.25, 4)
"""

from __future__ import annotations

import dataclasses
import math
from typing import Iterable, Mapping

import numpy as np


@dataclasses.dataclass(frozen=True)
class KienzleFit:
    """``kc11`` [Pa = N/m^2; /1e6 gives N/mm^2], ``mc`` [1], the coefficient of determination of the log
    fit, the largest relative error of F_c over the rows, the number of rows and the h range [m]."""

    kc11: float
    mc: float
    r2: float
    max_rel_error: float
    n: int
    h_range: tuple[float, float]

    def force(self, h: float, b: float) -> float:
        """F_c [N] for uncut chip thickness ``h`` and width ``b`` [m]."""
        return b * 1e3 * self.kc11 * 1e-6 * (h * 1e3) ** (1.0 - self.mc)

    def as_dict(self) -> dict:
        return {"kc11_N_per_mm2": self.kc11 / 1e6, "mc": self.mc, "r2": self.r2,
                "max_rel_error": self.max_rel_error, "rows": self.n,
                "h_min_mm": self.h_range[0] * 1e3, "h_max_mm": self.h_range[1] * 1e3}


def fit(rows: Iterable[Mapping[str, float]], h: str = "h", b: str = "b", force: str = "Fc") -> KienzleFit:
    """Fit Kienzle's law to ``rows`` with uncut chip thickness ``rows[h]`` [m], width ``rows[b]`` [m] and
    cutting force ``rows[force]`` [N]; needs two distinct h values or more."""
    data = [(float(r[h]), float(r[b]), float(r[force])) for r in rows]
    if any(not (hh > 0 and bb > 0 and ff > 0) for hh, bb, ff in data):
        raise ValueError("Kienzle fit: every row needs h > 0, b > 0 and F_c > 0")
    hs = np.array([d[0] for d in data]) * 1e3        # mm
    bs = np.array([d[1] for d in data]) * 1e3        # mm
    fc = np.array([d[2] for d in data])              # N
    if len(np.unique(hs)) < 2:
        raise ValueError("Kienzle fit: needs rows at two uncut chip thicknesses or more")
    x, y = np.log(hs), np.log(fc / bs)
    slope, intercept = np.polyfit(x, y, 1)
    pred = intercept + slope * x
    ss_res, ss_tot = float(np.sum((y - pred) ** 2)), float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else 1.0
    rel = np.abs(np.exp(pred) * bs / fc - 1.0)
    return KienzleFit(kc11=math.exp(float(intercept)) * 1e6, mc=1.0 - float(slope), r2=r2, max_rel_error=float(rel.max()),
                      n=len(data), h_range=(float(hs.min()) * 1e-3, float(hs.max()) * 1e-3))


def fit_groups(rows: Iterable[Mapping[str, float]], by: tuple[str, ...], **keys) -> dict[tuple, KienzleFit]:
    """One fit per group of rows sharing the values of the keys ``by`` (e.g. ``("speed", "rake")``)."""
    groups: dict[tuple, list] = {}
    for r in rows:
        groups.setdefault(tuple(r[k] for k in by), []).append(r)
    return {k: fit(v, **keys) for k, v in sorted(groups.items())}
