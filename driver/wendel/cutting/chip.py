"""What a cut reports, from forces and the chip's shape: shear and friction angles, chip thickness, steady state.

Pure functions for the FE chip formation to call on its histories and deformed meshes (and for experiments):

* the shear angle from the chip ratio ``r = h / h'``: ``tan(phi) = r cos(alpha) / (1 - r sin(alpha))``;
* the rake-face friction angle from the forces (Merchant's circle): ``lambda = alpha + atan(F_t / F_c)``;
* the chip thickness: distances of the chip's free (back) surface from the rake face line, in a band of the
  rake face away from the edge;
* the steady state: the first length of cut over which every series stays within a relative band (2 %),
  with the steady values and their spread.

>>> round(math.degrees(shear_angle(0.15e-3, 0.4155e-3, math.radians(-7))), 2)   # Oxley's case: 18.94 deg
18.94
>>> round(math.degrees(friction_angle(574.93, 351.74, math.radians(-7))), 2)     # and its 24.46 deg
24.46
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np


def shear_angle(h: float, h_chip: float, rake: float) -> float:
    """Shear angle [rad] of a chip of thickness ``h_chip`` cut at uncut thickness ``h`` with ``rake`` [rad]."""
    if not (h > 0 and h_chip > 0):
        raise ValueError("shear angle: needs h > 0 and a chip thickness h' > 0")
    r = h / h_chip
    return math.atan2(r * math.cos(rake), 1.0 - r * math.sin(rake))


def friction_angle(Fc: float, Ft: float, rake: float) -> float:
    """Mean friction angle [rad] on the rake face from the cutting and thrust forces (sharp tool)."""
    if Fc <= 0:
        raise ValueError("friction angle: needs a positive cutting force")
    return rake + math.atan2(Ft, Fc)


def chip_thickness(points: np.ndarray, rake_point: np.ndarray, rake: float, band: tuple[float, float],
                   mesh: tuple[np.ndarray, np.ndarray] | None = None) -> tuple[float, float]:
    """Median and spread (max - min) [m] of the distance of the chip's back-surface ``points`` (n, 2) from the
    rake face line through ``rake_point`` at ``rake`` [rad], over the points whose position along the rake
    face (from ``rake_point``, upwards) lies in ``band = (s0, s1)`` [m].

    With ``mesh = (nodes, triangles)`` (the deformed body), only the points of the chip's first layer count: a
    point further from the rake face than the end of the first stretch of material on the rake face's normal
    through it (:func:`first_layer_ends`) belongs to a part of the chip that has curled back over the band (its
    inner or outer surface), not to the back surface; before session 33 such points doubled and tripled the
    median of a long titanium cut."""
    points = np.asarray(points, dtype=float)
    along = np.array([math.sin(rake), math.cos(rake)])
    normal = np.array([-math.cos(rake), math.sin(rake)])      # towards the chip
    rel = points - np.asarray(rake_point, dtype=float)
    s, d = rel @ along, rel @ normal
    pick = (s >= band[0]) & (s <= band[1]) & (d > 0)
    if pick.any() and mesh is not None:
        ends = first_layer_ends(*mesh, rake_point, rake, s[pick])
        keep = d[pick] <= ends * (1 + 1e-9) + 1e-12 * (abs(band[1]) + abs(band[0]))
        pick[np.flatnonzero(pick)[~keep]] = False
    if not pick.any():
        raise ValueError(f"chip thickness: no chip surface point {band[0]:g}-{band[1]:g} m up the rake face")
    return float(np.median(d[pick])), float(d[pick].max() - d[pick].min())


def first_layer_ends(nodes: np.ndarray, triangles: np.ndarray, rake_point, rake: float, s) -> np.ndarray:
    """Distance from the rake face line (through ``rake_point`` at ``rake`` [rad]) at which the first stretch of
    material on its normal at each ``s`` [m] up the face ends: the triangles the normal line crosses give intervals
    of distance (d >= 0), merged where they touch; the end of the one nearest the face. ``inf`` where the line
    crosses no triangle. The nodes are projected once for all ``s``.

    >>> nodes = np.array([[0.0, 0.0], [-1.0, 0.0], [-1.0, 2.0], [0.0, 2.0], [-2.0, 0.0], [-3.0, 0.0],
    ...                   [-3.0, 2.0], [-2.0, 2.0]])      # two strips beside a vertical rake face, a gap between
    >>> tri = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    >>> first_layer_ends(nodes, tri, [0.0, 0.0], 0.0, [1.0, 3.0]).tolist()
    [1.0, inf]
    """
    along = np.array([math.sin(rake), math.cos(rake)])
    normal = np.array([-math.cos(rake), math.sin(rake)])
    rel = np.asarray(nodes, dtype=float)[:, :2] - np.asarray(rake_point, dtype=float)
    u0, v = rel @ along, rel @ normal                # along the face, and the distance from it
    tri = np.asarray(triangles)
    edges = [(u0[tri[:, a]], u0[tri[:, b]], v[tri[:, a]], v[tri[:, b]]) for a, b in ((0, 1), (1, 2), (2, 0))]
    tol = 1e-9 * max(float(np.abs(v).max()), 1e-300)
    out = []
    for si in np.atleast_1d(np.asarray(s, dtype=float)):
        lo, hi = np.full(len(tri), np.inf), np.full(len(tri), -np.inf)
        for ua0, ub0, va, vb in edges:             # the line is u = s: where each edge crosses it
            ua, ub = ua0 - si, ub0 - si
            cross = (ua * ub <= 0) & (ua != ub)
            t = np.divide(ua, ua - ub, out=np.zeros_like(ua), where=cross)
            vc = va + t * (vb - va)
            lo = np.where(cross, np.minimum(lo, vc), lo)
            hi = np.where(cross, np.maximum(hi, vc), hi)
        ok = (hi >= lo) & (hi > 0)
        if not ok.any():
            out.append(math.inf)
            continue
        order = np.argsort(np.maximum(lo[ok], 0.0))
        lo_s, hi_s = np.maximum(lo[ok], 0.0)[order], hi[ok][order]
        end = hi_s[0]
        for a, b in zip(lo_s[1:], hi_s[1:]):
            if a > end + tol:
                break
            end = max(end, b)
        out.append(float(end))
    return np.array(out)


@dataclasses.dataclass(frozen=True)
class Steady:
    """Where the steady state starts (``start``, in the unit of the cut length given), the window's
    end, the steady values (window means) and their relative spreads ((max - min) / |mean|)."""

    start: float
    end: float
    values: dict
    spreads: dict


def steady_state(x, series: dict, length: float, tol: float = 0.02) -> Steady | None:
    """The first window ``[x_i, x_i + length]`` of the cut over which every series of ``series`` (name ->
    values at the cut lengths ``x``) stays within ``tol`` relative spread; None if the cut never settles."""
    x = np.asarray(x, dtype=float)
    if len(x) < 2 or np.any(np.diff(x) <= 0):
        raise ValueError("steady state: needs two or more increasing cut lengths")
    ys = {k: np.asarray(v, dtype=float) for k, v in series.items()}
    if any(len(v) != len(x) for v in ys.values()):
        raise ValueError("steady state: every series needs one value per cut length")
    for i in range(len(x)):
        j = np.searchsorted(x, x[i] + length * (1 - 1e-12), side="left")
        if j >= len(x):
            return None
        window = slice(i, j + 1)
        spreads = {}
        for k, v in ys.items():
            w = v[window]
            mean = float(w.mean())
            spreads[k] = float(w.max() - w.min()) / abs(mean) if mean != 0 else math.inf
        if all(s <= tol for s in spreads.values()):
            return Steady(start=float(x[i]), end=float(x[j]),
                          values={k: float(v[window].mean()) for k, v in ys.items()}, spreads=spreads)
    return None
