"""Material removal: the heat of the removed slice and a conservative transfer of the temperature.

Used by the drilling loop (:mod:`wendel.loop.drilling`); the geometry of the bore is
:mod:`wendel.meshes.drilling`.
"""

from __future__ import annotations

import math

import numpy as np

from ..meshes import drilling as geometry
from . import transfer
from .step import cell_volumes


# Degree-2 rules with interior points (Keast 1986 for the tetrahedron; Strang-Fix for the triangle):
# barycentric points and weights (sum 1).
_A3, _B3 = 0.5854101966249685, 0.1381966011250105
RULES = {3: (np.array([[_A3, _B3, _B3, _B3], [_B3, _A3, _B3, _B3], [_B3, _B3, _A3, _B3], [_B3, _B3, _B3, _A3]]),
             np.full(4, 0.25)),
         2: (np.array([[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]]), np.full(3, 1 / 3))}


def conservative_transfer(old_points, old_cells, values, new_points, new_cells, axisymmetric: bool = False):
    """Nodal field onto a new mesh by the lumped L2 projection ``v_i = int phi_i v_old / int phi_i``.

    ``axisymmetric``: (r, z) triangles, every integral weighted by r (``v_i = int r phi_i v_old / int r phi_i``),
    so the integral over the body of revolution ``2 pi int r v`` is the one kept.

    For P1 the integral of the result is ``sum_i v_i int phi_i``, i.e. the quadrature of ``int v_old`` over
    the new mesh: the heat the new body holds is the heat the old field had there (exact where the old
    field is linear on a new element; the quadrature sees the kinks of the old field only to second
    order), and the weights are positive, so no new extrema (interpolation instead adds O(h^2 v'') per
    transfer, always of the sign of the field's curvature). Returns ``(values, points outside)``.

    >>> p = np.array([[0., 0], [1, 0], [1, 1], [0, 1]]); t = np.array([[0, 1, 2], [0, 2, 3]])
    >>> v, _ = conservative_transfer(p, t, p[:, 0] ** 2, p[::-1], t[:, ::-1])
    >>> a = cell_volumes(p, t); bool(abs(a @ transfer.nodes_to_cells(t, v) - a @ transfer.nodes_to_cells(t, p[:, 0] ** 2)) < 1e-15)
    True
    """
    if transfer._same_mesh(old_points, old_cells, new_points, new_cells):
        return np.asarray(values, dtype=float).copy(), 0          # nothing removed: the identity
    dim = new_cells.shape[1] - 1
    bary, w = RULES[dim]
    pts = np.asarray(new_points, dtype=float)[:, :dim]
    q = quadrature_points(pts, new_cells)
    vq, outside = transfer.transfer_nodal(old_points, old_cells, values, q)
    vq = vq.reshape(len(new_cells), len(w))
    vol = cell_volumes(pts, new_cells)
    # r at the quadrature points: the weight of (r, z) integrals (the rule is exact for r phi_j: degree 2)
    rq = q[:, 0].reshape(len(new_cells), len(w)) if axisymmetric else np.ones((len(new_cells), len(w)))
    # int phi_j v (r) over a cell: sum_q w_q |K| bary_qj v_q (r_q)
    contrib = vol[:, None] * np.einsum("q,qj,cq->cj", w, bary, vq * rq)
    cell_mass = vol[:, None] * np.einsum("q,qj,cq->cj", w, bary, rq)
    mass = np.bincount(new_cells.ravel(), weights=cell_mass.ravel(), minlength=len(pts))
    load = np.bincount(new_cells.ravel(), weights=contrib.ravel(), minlength=len(pts))
    return load / mass, outside


def quadrature_points(new_points, new_cells) -> np.ndarray:
    """The points of :func:`conservative_transfer`'s rule in every new cell, cell by cell ((m * q, d))."""
    dim = new_cells.shape[1] - 1
    pts = np.asarray(new_points, dtype=float)[:, :dim]
    return np.einsum("qj,cjk->cqk", RULES[dim][0], pts[new_cells]).reshape(-1, dim)


def removed_slice_quadrature(d0: float, d1: float, radius: float, point_angle: float, height: float,
                             axis=(0.0, 0.0), n_r: int = 6, n_s: int = 6, n_theta: int = 48):
    """Points (m) and weights (m^3) integrating over the slice B(d1) - B(d0) of the bore.

    ``n_theta = 1`` gives the (r, z) rule of an axisymmetric section: the points (r, 0, z) and the weights of
    the volume of revolution (2 pi r dr ds); take the columns 0 and 2.

    Gauss-Legendre in r on the pieces between the kinks of the profiles, in the depth s between the two
    profiles, and the trapezoidal rule in theta (exact for trigonometric polynomials). The weights sum to
    V(d1) - V(d0) to round-off:

    >>> _, w = removed_slice_quadrature(0.002, 0.005, 0.003, 118.0, 0.02)
    >>> bool(abs(w.sum() - (geometry.bore_volume(0.005, 0.003, 118.0) - geometry.bore_volume(0.002, 0.003, 118.0))) < 1e-18)
    True
    """
    if d1 <= d0:
        return np.zeros((0, 3)), np.zeros(0)
    cot = 1 / math.tan(math.radians(point_angle) / 2)
    kinks = sorted({0.0, radius, *(min(radius, d / cot) for d in (d0, d1) if d > 0)})
    xr, wr = np.polynomial.legendre.leggauss(n_r)
    xs, ws = np.polynomial.legendre.leggauss(n_s)
    theta = 2 * math.pi * np.arange(n_theta) / n_theta
    P, W = [], []
    for a, b in zip(kinks[:-1], kinks[1:]):
        r = 0.5 * (b - a) * xr + 0.5 * (a + b)
        w_r = 0.5 * (b - a) * wr
        s_lo, s_hi = np.maximum(0.0, d0 - r * cot), np.maximum(0.0, d1 - r * cot)
        for ri, wri, lo, hi in zip(r, w_r, s_lo, s_hi):
            if hi <= lo:
                continue
            s = 0.5 * (hi - lo) * xs + 0.5 * (hi + lo)
            w_s = 0.5 * (hi - lo) * ws
            for si, wsi in zip(s, w_s):
                P.append(np.column_stack([axis[0] + ri * np.cos(theta), axis[1] + ri * np.sin(theta),
                                          np.full(n_theta, height - si)]))
                W.append(np.full(n_theta, wri * wsi * ri * 2 * math.pi / n_theta))
    return np.vstack(P), np.concatenate(W)


