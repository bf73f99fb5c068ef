"""The largest temperatures of the primary and the secondary shear zone of one FE cut increment.

The zones are geometric, measured on the current positions (mm) of the increment:

- **secondary zone** (tool-chip): the material within ``SECONDARY * h`` of the tool's surface (the rake face,
  the rounded edge) on the rake side of the tip (a point's distance from the tip along the rake face >= 0);
  the flank side (the machined surface) is in neither zone;
- **primary zone** (the chip root's shear band): the material within ``PRIMARY * h`` of the shear plane, the
  segment from the tip ahead of the tool up to the top of the uncut layer (y = h) at the shear angle phi
  (from the increment's chip ratio; Oxley's phi, or 20 deg, while the chip has no thickness yet), above the
  tip (the rake side), the material within ``SECONDARY * h`` of the tool left out (the edge and the rake face:
  the secondary zone; below the tip the flank's, in neither zone).

Temperatures: the nodal field ``T`` of a conducting cut, or the cell field ``T`` (at the cells' centroids) of an
adiabatic one. NaN where a zone holds no point.

>>> pts = np.array([[0.0, 0.001], [-0.1, 0.05], [-0.5, 0.05], [0.05, 0.1], [-0.02, -0.005]])
>>> outline = np.array([[0.0, 0.0], [0.5, 1.0], [1.0, 1.0], [1.0, 0.0]])  # a wedge: tip at the origin
>>> z = zones(pts, outline, np.zeros(2), math.radians(0.0), 0.15, math.radians(30))
>>> z["secondary"].tolist(), z["primary"].tolist()
([True, False, False, True, False], [False, True, False, False, False])
"""

from __future__ import annotations

import math

import numpy as np

SECONDARY = 0.2   # the secondary zone: within 0.2 h (30 um on the steel scene) of the tool's surface
PRIMARY = 0.25    # the primary zone: within 0.25 h of the shear plane (either side)
PHI_DEFAULT = 20.0  # deg: the shear plane before the chip has a thickness and Oxley has no solution


def distance_to_outline(points: np.ndarray, outline: np.ndarray) -> np.ndarray:
    """Distance of each point from the closed polyline ``outline`` (its segments)."""
    a = outline
    b = np.roll(outline, -1, axis=0)
    ab = b - a
    L2 = np.maximum((ab ** 2).sum(axis=1), 1e-300)
    d = np.full(len(points), np.inf)
    for k in range(len(a)):           # a tool outline has ~30 segments: a loop over them, vectorised in the points
        t = np.clip(((points - a[k]) @ ab[k]) / L2[k], 0.0, 1.0)
        d = np.minimum(d, np.linalg.norm(points - (a[k] + t[:, None] * ab[k]), axis=1))
    return d


def zones(points: np.ndarray, outline: np.ndarray, tip: np.ndarray, rake: float, h: float, phi: float) -> dict:
    """Boolean masks ``secondary`` and ``primary`` of ``points`` (see the module); the tool moves in -x, its
    rake face runs up along (sin rake, cos rake) from the ``tip``."""
    along = (points - tip) @ np.array([math.sin(rake), math.cos(rake)])
    near = distance_to_outline(points, outline) <= SECONDARY * h
    secondary = near & (along >= 0)
    e = np.array([-math.cos(phi), math.sin(phi)])        # up the shear plane, ahead of the tool
    n = np.array([e[1], -e[0]])
    s = (points - tip) @ e
    primary = (s >= 0) & (s <= h / max(math.sin(phi), 1e-3)) & (np.abs((points - tip) @ n) <= PRIMARY * h) \
        & ~near & (along >= 0)
    return {"secondary": secondary, "primary": primary}


def zone_temperatures(mesh, outline: np.ndarray, tip: np.ndarray, rake: float, h: float, phi: float) -> dict:
    """``max_T_primary_K`` and ``max_T_secondary_K`` of a meshio mesh of the increment (positions in mm)."""
    pts = np.asarray(mesh.points)[:, :2]
    if "T" in mesh.point_data:
        where, T = pts, np.asarray(mesh.point_data["T"], dtype=float).ravel()
    elif "T" in mesh.cell_data:
        cells = mesh.cells_dict["triangle"]
        where, T = pts[cells].mean(axis=1), np.asarray(mesh.cell_data["T"][0], dtype=float).ravel()
    else:
        return {"max_T_primary_K": float("nan"), "max_T_secondary_K": float("nan")}
    z = zones(where, outline, tip, rake, h, phi)
    pick = lambda m: float(T[m].max()) if m.any() else float("nan")
    return {"max_T_primary_K": pick(z["primary"]), "max_T_secondary_K": pick(z["secondary"])}
