"""Element quality of a (deformed) simplex mesh: signed inverse condition number, gamma, inverted elements.

The driver calls :func:`mesh_quality` after each accepted increment, on the deformed configuration
``points + u``, and remeshes when the worst element falls below the scene's threshold (or any element
is inverted). Everything is computed with numpy from the element Jacobians, so it needs no gmsh session;
the measures are those of gmsh (``getElementQualities``) for linear simplices:

- ``sicn``: signed inverse condition number of the Jacobian taken from the equilateral reference
  element, ``d sign(det S) / (||S||_F ||S^-1||_F)`` with ``S = J W^-1`` (gmsh's ``minSICN``; in 2D it equals
  the mean ratio). 1 for an equilateral element, 0 for a degenerate one, negative when inverted.
- ``gamma``: ``d`` times inscribed over circumscribed radius (gmsh's ``gamma``), in [0, 1], unsigned.

An element is *inverted* when its signed measure is not positive. Signs are taken relative to
``reference`` (the undeformed points) when given, so that either orientation convention works; without
a reference the gmsh/FreeFEM convention applies (counter-clockwise triangles in the xy plane, tetrahedra
with a positive Jacobian).

>>> import numpy as np
>>> tri = np.array([[0, 0], [1, 0], [0.5, np.sqrt(3) / 2]])
>>> q = mesh_quality(tri, [[0, 1, 2]])
>>> round(q["min"], 12), q["inverted"]
(1.0, 0)
>>> mesh_quality(tri, [[0, 2, 1]])["inverted"]
1
"""

from __future__ import annotations

import numpy as np

__all__ = ["mesh_quality", "signed_measure", "sicn", "gamma", "DEFAULT_THRESHOLDS"]

#: Remesh triggers used when a scene gives none: the worst SICN of the deformed mesh, and inverted elements.
#: 0.1 is well above the 0.01 where iterative solvers and gradient recovery degrade, and well below the
#: 0.3-0.5 of a fresh gmsh mesh, so remeshing happens only for real distortion.
DEFAULT_THRESHOLDS = {"min_sicn": 0.1, "max_inverted": 0}


def _as_arrays(points, cells):
    cells = np.asarray(cells, dtype=np.int64)
    if cells.ndim != 2 or cells.shape[1] not in (3, 4):
        raise ValueError(f"cells must be (n, 3) triangles or (n, 4) tetrahedra, got shape {cells.shape}")
    dim = cells.shape[1] - 1
    points = np.asarray(points, dtype=float)
    if points.ndim == 1:
        points = points.reshape(-1, dim)
    return points[:, :dim], cells, dim


def _edge_matrix(points, cells):
    """Jacobians ``J[k] = [x1 - x0, x2 - x0(, x3 - x0)]`` (columns), shape (n, d, d)."""
    x0 = points[cells[:, 0]]
    return np.stack([points[cells[:, i]] - x0 for i in range(1, cells.shape[1])], axis=-1)


# Inverse of the Jacobian of the unit-edge equilateral simplex, (d, d), columns = edges from vertex 0.
_W_INV = {
    2: np.linalg.inv(np.array([[1.0, 0.5], [0.0, np.sqrt(3) / 2]])),
    3: np.linalg.inv(np.array([[1.0, 0.5, 0.5], [0.0, np.sqrt(3) / 2, np.sqrt(3) / 6], [0.0, 0.0, np.sqrt(6) / 3]])),
}


def signed_measure(points, cells):
    """Signed area (triangles) or volume (tetrahedra) of each cell.

    >>> signed_measure([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]]).tolist()
    [0.5]
    """
    points, cells, dim = _as_arrays(points, cells)
    return np.linalg.det(_edge_matrix(points, cells)) / (2.0 if dim == 2 else 6.0)


def sicn(points, cells):
    """Signed inverse condition number of each linear simplex (gmsh's SICN); 1 is equilateral.

    >>> round(float(sicn([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]])[0]), 6)
    0.866025
    """
    points, cells, dim = _as_arrays(points, cells)
    s = _edge_matrix(points, cells) @ _W_INV[dim]
    det = np.linalg.det(s)
    norm = np.sqrt(np.einsum("kij,kij->k", s, s))
    if dim == 2:
        norm_adj = norm  # the adjugate of a 2x2 matrix is a signed permutation of it
    else:
        c = [s[:, :, i] for i in range(3)]
        norm_adj = np.sqrt(sum(np.einsum("ki,ki->k", v, v) for v in
                               (np.cross(c[1], c[2]), np.cross(c[2], c[0]), np.cross(c[0], c[1]))))
    # ||S^-1||_F = ||adj S||_F / |det S|, so d / (||S|| ||S^-1||) = d det / (||S|| ||adj S||).
    with np.errstate(divide="ignore", invalid="ignore"):
        q = dim * det / (norm * norm_adj)
    return np.nan_to_num(q, nan=0.0, posinf=0.0, neginf=0.0)


def gamma(points, cells):
    """``d`` times inscribed over circumscribed radius of each simplex (1 equilateral, 0 degenerate).

    >>> round(float(gamma([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], [[0, 1, 2, 3]])[0]), 6)
    0.732051
    """
    points, cells, dim = _as_arrays(points, cells)
    meas = np.abs(signed_measure(points, cells))
    x = points[cells]
    if dim == 2:
        a = np.linalg.norm(x[:, 1] - x[:, 2], axis=1)
        b = np.linalg.norm(x[:, 2] - x[:, 0], axis=1)
        c = np.linalg.norm(x[:, 0] - x[:, 1], axis=1)
        r_in = 2 * meas / (a + b + c)
        r_out = a * b * c / (4 * meas)
    else:
        faces = [(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)]
        area = sum(0.5 * np.linalg.norm(np.cross(x[:, j] - x[:, i], x[:, k] - x[:, i]), axis=1) for i, j, k in faces)
        r_in = 3 * meas / area
        # Circumcentre c solves 2 (x_i - x_0) . c' = |x_i - x_0|^2 with c' = c - x_0.
        e = x[:, 1:] - x[:, :1]
        with np.errstate(divide="ignore", invalid="ignore"):
            cc = np.linalg.solve(2 * e + 1e-300 * np.eye(3), np.einsum("kij,kij->ki", e, e)[..., None])[..., 0]
        r_out = np.linalg.norm(cc, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = dim * r_in / r_out
    return np.nan_to_num(q, nan=0.0, posinf=0.0)


def mesh_quality(points, cells, reference=None, with_gamma=False):
    """Quality summary of a triangle or tetrahedron mesh.

    Parameters
    ----------
    points : array_like, (n, 2) or (n, 3)
        Node coordinates of the configuration to judge (deformed: ``X + u``). Extra columns are ignored.
    cells : array_like, (m, 3) or (m, 4)
        Node indices (0-based) of triangles or tetrahedra.
    reference : array_like, optional
        Undeformed coordinates: an element is inverted when its signed measure changed sign from there.
    with_gamma : bool
        Also compute gamma per cell (a little slower in 3D).

    Returns
    -------
    dict
        ``min``, ``mean`` (of SICN), ``inverted`` (count), ``per_cell`` (SICN, (m,), negative when
        inverted), ``worst`` (index of the worst cell), ``min_measure`` (smallest signed area/volume,
        oriented) and, with ``with_gamma``, ``gamma_min`` and ``gamma``.

    Examples
    --------
    >>> pts = [[0, 0], [1, 0], [1, 1], [0, 1]]
    >>> q = mesh_quality(pts, [[0, 1, 2], [0, 2, 3]])
    >>> round(q["min"], 6), q["inverted"], q["per_cell"].shape
    (0.866025, 0, (2,))
    """
    points, cells, dim = _as_arrays(points, cells)
    q = sicn(points, cells)
    meas = signed_measure(points, cells)
    if reference is not None:
        flip = np.sign(signed_measure(reference, cells))
        flip[flip == 0] = 1.0
        q = q * flip
        meas = meas * flip
    q = np.where(meas > 0, np.abs(q), -np.abs(q))
    out = {
        "min": float(q.min()) if q.size else 1.0,
        "mean": float(q.mean()) if q.size else 1.0,
        "inverted": int(np.count_nonzero(meas <= 0)),
        "per_cell": q,
        "worst": int(np.argmin(q)) if q.size else -1,
        "min_measure": float(meas.min()) if q.size else 0.0,
    }
    if with_gamma:
        g = gamma(points, cells)
        out["gamma"] = g
        out["gamma_min"] = float(g.min()) if g.size else 1.0
    return out


def needs_remesh(quality, min_sicn=DEFAULT_THRESHOLDS["min_sicn"], max_inverted=DEFAULT_THRESHOLDS["max_inverted"]):
    """Whether a :func:`mesh_quality` result calls for a remesh; returns ``(bool, reason)``.

    >>> needs_remesh({"min": 0.05, "inverted": 0})
    (True, 'min SICN 0.05 < 0.1')
    """
    if quality["inverted"] > max_inverted:
        return True, f"{quality['inverted']} inverted elements"
    if quality["min"] < min_sicn:
        return True, f"min SICN {quality['min']:.3g} < {min_sicn:.3g}"
    return False, ""
