"""Transfer of state fields from an old simplex mesh to a new one (after a remesh).

- Nodal P1 fields (displacement, temperature, a contact indicator; any number of components) are
  interpolated linearly in the old element that contains each new node (barycentric coordinates).
- Cell fields (equivalent plastic strain ``p``, plastic strain tensor ``epsp``, hardening variable; P0 or
  quadrature values averaged per cell) are first recovered to nodes, by a volume-weighted average
  (lumped L2 projection: monotone, keeps ``p >= 0``) or by the consistent L2 projection, then
  interpolated like nodal fields and averaged back over the vertices of each new cell (the exact cell
  mean of the P1 field). Both recoveries conserve the integral exactly; the interpolation changes it
  by O(h^2) for smooth fields.

Policy for new nodes outside the old mesh (a remeshed boundary cuts a curved old boundary, round-off):
a node is inside when all its barycentric coordinates are >= ``-tol`` (default 1e-9) in some old
element; otherwise it takes the value interpolated at the nearest point of the old boundary (closest
point on the nearest boundary edge or face). Their number is returned as ``n_outside``.

Points are located with a cKDTree of element centroids: candidates are the ``k`` nearest centroids
(k = 8, then 32), and for the few points left a ball query with the largest centroid-vertex distance,
which is guaranteed to contain the element of any inside point.

Size: about 380 lines on purpose: one algorithm, point location (:func:`locate`, with the closest-point
fallback for outside nodes) and the nodal, cell and active-set transfers that are thin layers on it;
split, the locator would sit apart from its only users.

>>> import numpy as np
>>> pts = np.array([[0., 0], [1, 0], [1, 1], [0, 1]])
>>> tri = np.array([[0, 1, 2], [0, 2, 3]])
>>> v, out = transfer_nodal(pts, tri, pts[:, 0] + 2 * pts[:, 1], [[0.25, 0.5], [2.0, 0.5]])
>>> v.round(12).tolist(), out
([1.25, 2.0], 1)
"""

from __future__ import annotations

import numpy as np

from .quality import _as_arrays, signed_measure

__all__ = ["locate", "transfer_nodal", "cell_to_nodes", "nodes_to_cells", "transfer_cell", "transfer_active_set"]




def _boundary(cells):
    from .mesher import boundary_facets

    return boundary_facets(cells)


def _closest_on_facets(points, facets, query):
    """Closest point on a set of segments (2D) or triangles (3D): ``(facet index, weights on its nodes)``."""
    dim = points.shape[1]
    centroids = points[facets].mean(axis=1)
    k = min(8, len(facets))
    from scipy.spatial import cKDTree      # here: scipy (0.5 s) is imported while FreeFEM solves (overlap.preload)

    _, cand = cKDTree(centroids).query(query, k=k)
    cand = cand.reshape(len(query), k)
    best_d = np.full(len(query), np.inf)
    best_f = np.zeros(len(query), dtype=np.int64)
    best_w = np.zeros((len(query), dim))
    for j in range(k):
        f = cand[:, j]
        a = points[facets[f, 0]]
        b = points[facets[f, 1]]
        if dim == 2:
            ab = b - a
            t = np.clip(np.einsum("ij,ij->i", query - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
            w = np.column_stack([1 - t, t])
        else:
            w = _closest_on_triangle(query, a, b, points[facets[f, 2]])
        xc = np.einsum("ij,ijk->ik", w, points[facets[f]])
        d = np.linalg.norm(query - xc, axis=1)
        better = d < best_d
        best_d[better], best_f[better], best_w[better] = d[better], f[better], w[better]
    return best_f, best_w


def _closest_on_triangle(p, a, b, c):
    """Barycentric weights (n, 3) of the closest point of triangles (a, b, c) to points p (Ericson's method)."""
    n = len(p)
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    w = np.zeros((n, 3))
    done = np.zeros(n, dtype=bool)

    def put(mask, weights):
        m = mask & ~done
        w[m] = weights[m] if weights.ndim == 2 else weights
        done[m] = True

    one = np.ones(n)
    zero = np.zeros(n)
    with np.errstate(divide="ignore", invalid="ignore"):
        put((d1 <= 0) & (d2 <= 0), np.array([1.0, 0, 0]))
        put((d3 >= 0) & (d4 <= d3), np.array([0, 1.0, 0]))
        put((d6 >= 0) & (d5 <= d6), np.array([0, 0, 1.0]))
        t = d1 / (d1 - d3)
        put((vc <= 0) & (d1 >= 0) & (d3 <= 0), np.column_stack([one - t, t, zero]))
        t = d2 / (d2 - d6)
        put((vb <= 0) & (d2 >= 0) & (d6 <= 0), np.column_stack([one - t, zero, t]))
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        put((va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0), np.column_stack([zero, one - t, t]))
        den = va + vb + vc
        v, ww = vb / den, vc / den
        put(np.ones(n, dtype=bool), np.column_stack([one - v - ww, v, ww]))
    return np.nan_to_num(w)


class _Locator:
    """What :func:`locate` needs of one old mesh, computed once: the first vertices, the inverse Jacobians,
    the centroids' cKDTree and the largest centroid-vertex distance (the drilling loop locates several point
    sets in one mesh: the new nodes, the new quadrature points, the removed slice, the probes)."""

    def __init__(self, pts, cells, dim):
        self.n = len(cells)
        self.x0 = pts[cells[:, 0]]
        jac = np.stack([pts[cells[:, i]] - self.x0 for i in range(1, dim + 1)], axis=-1)
        self.inv = np.linalg.inv(jac)
        self.centroids = pts[cells].mean(axis=1)
        from scipy.spatial import cKDTree

        self.tree = cKDTree(self.centroids)
        self._radius, self._pts, self._cells = None, pts, cells

    @property
    def radius(self):
        if self._radius is None:
            self._radius = np.linalg.norm(self._pts[self._cells] - self.centroids[:, None, :], axis=2).max() * (1 + 1e-9)
        return self._radius


_LOCATORS: dict = {}
"""Recent meshes' :class:`_Locator` by the bytes of their points and cells (a few: they are small)."""


def _digest(a: np.ndarray) -> tuple:
    import hashlib

    return a.shape, a.dtype.str, hashlib.blake2b(np.ascontiguousarray(a)).digest()


def _locator(pts, cells, dim) -> tuple[_Locator, tuple]:
    key = (_digest(pts), _digest(cells))
    loc = _LOCATORS.pop(key, None)
    if loc is None:
        loc = _Locator(pts, cells, dim)
    _LOCATORS[key] = loc                      # the most recent last
    while len(_LOCATORS) > 4:
        del _LOCATORS[next(iter(_LOCATORS))]
    return loc, key


_LOCATED: dict = {}
"""Recent :func:`locate` answers by mesh, points and tolerance (the drilling loop locates each point set while
FreeFEM solves, :mod:`wendel.loop.lookahead`, and again after it: the same arrays, not searched twice)."""


def locate(old_points, old_cells, new_points, tol=1e-9):
    """Find the old element containing each new point.

    Parameters
    ----------
    old_points, old_cells : array_like
        The old mesh: coordinates (n, >= d) and simplices (m, d + 1).
    new_points : array_like
        Points to locate (p, >= d).
    tol : float
        A point is inside an element when all barycentric coordinates are >= ``-tol``.

    Returns
    -------
    cell : ndarray (p,)
        Index of the containing element, -1 when outside the old mesh.
    bary : ndarray (p, d + 1)
        Barycentric coordinates in that element (clipped to >= 0 and renormalized).
    """
    pts, cells, dim = _as_arrays(old_points, old_cells)
    q = np.asarray(new_points, dtype=float)
    q = q.reshape(-1, dim) if q.ndim == 1 else q[:, :dim]
    loc, key = _locator(pts, cells, dim)
    key = (key, _digest(q), tol)
    if key in _LOCATED:
        cell, bary = _LOCATED[key]
        return cell.copy(), bary.copy()
    inv, x0 = loc.inv, loc.x0
    cell = np.full(len(q), -1, dtype=np.int64)
    bary = np.zeros((len(q), dim + 1))

    def test(idx, cand):
        """Try candidate cells cand (len(idx), k) for points idx; keep the one with the largest min coordinate
        (the first of equals), all candidates at once."""
        valid = cand < loc.n
        c = np.where(valid, cand, 0)
        lam = np.einsum("nkij,nkj->nki", inv[c], q[idx][:, None, :] - x0[c])
        lam = np.concatenate([(1 - lam.sum(axis=2))[:, :, None], lam], axis=2)
        worst = np.where(valid, lam.min(axis=2), -np.inf)
        j = worst.argmax(axis=1)
        rows = np.arange(len(idx))
        best = worst[rows, j]
        some = best > -np.inf
        cell[idx[some]] = c[rows, j][some]
        bary[idx[some]] = lam[rows, j][some]
        cell[idx[best < -tol]] = -1

    todo = np.arange(len(q))
    for k in (8, 32):
        if len(todo) == 0:
            break
        k = min(k, loc.n)
        _, cand = loc.tree.query(q[todo], k=k)
        test(todo, cand.reshape(len(todo), k))
        todo = todo[cell[todo] < 0]
    if len(todo):
        for i, near in zip(todo, loc.tree.query_ball_point(q[todo], loc.radius)):
            if near:
                test(np.array([i]), np.array([near]))
    found = cell >= 0
    b = np.clip(bary[found], 0.0, None)
    bary[found] = b / b.sum(axis=1, keepdims=True)
    _LOCATED[key] = cell.copy(), bary.copy()
    while len(_LOCATED) > 12:
        del _LOCATED[next(iter(_LOCATED))]
    return cell, bary


def _as_nodal(values, n):
    """(n, m) view of nodal values given as (n,), (n, m) or interleaved (n * m,); and how to restore."""
    v = np.asarray(values, dtype=float)
    if v.ndim == 1 and v.size == n:
        return v[:, None], lambda a: a[:, 0]
    if v.ndim == 1 and v.size % n == 0:
        m = v.size // n
        return v.reshape(n, m), lambda a: a.reshape(-1)
    if v.ndim == 2 and v.shape[0] == n:
        return v, lambda a: a
    raise ValueError(f"values of shape {v.shape} do not match {n} nodes")


def transfer_nodal(old_points, old_cells, values, new_points, tol=1e-9):
    """Interpolate a P1 nodal field (any number of components) from an old mesh to new points.

    Parameters
    ----------
    old_points, old_cells : array_like
        Old mesh: coordinates (n, >= d), simplices (m, d + 1). For a deformed body pass the deformed
        old coordinates and the new mesh of the same deformed configuration.
    values : array_like
        Nodal values: (n,), (n, c), or interleaved per node (n * c,) as FreeFEM writes vector fields.
    new_points : array_like
        Nodes of the new mesh (p, >= d).
    tol : float
        Barycentric tolerance of the inside test.

    Returns
    -------
    values_new : ndarray
        Same layout as ``values`` ((p,), (p, c) or (p * c,)).
    n_outside : int
        New points outside the old mesh; they got the value at the nearest old boundary point.

    Examples
    --------
    >>> pts = [[0., 0], [1, 0], [0, 1]]
    >>> u = [0., 0, 1, 0, 0, 2]   # interleaved [ux0, uy0, ux1, uy1, ...]
    >>> v, out = transfer_nodal(pts, [[0, 1, 2]], u, [[0.5, 0.5]])
    >>> v.tolist(), out
    ([0.5, 1.0], 0)
    """
    pts, cells, dim = _as_arrays(old_points, old_cells)
    vals, restore = _as_nodal(values, len(pts))
    q = np.asarray(new_points, dtype=float)
    q = q.reshape(-1, dim) if q.ndim == 1 else q[:, :dim]
    cell, bary = locate(pts, cells, q, tol)
    out = np.einsum("pk,pkc->pc", bary, vals[cells[np.maximum(cell, 0)]])
    outside = np.flatnonzero(cell < 0)
    if len(outside):
        facets = _boundary(cells)
        f, w = _closest_on_facets(pts, facets, q[outside])
        out[outside] = np.einsum("pk,pkc->pc", w, vals[facets[f]])
    return restore(out), int(len(outside))


def cell_to_nodes(points, cells, cell_values, method="volume", axisymmetric=False):
    """Recover a cell field (P0, or quadrature values averaged per cell) to a continuous P1 field.

    Parameters
    ----------
    points, cells : array_like
        Mesh coordinates (n, >= d) and simplices (m, d + 1).
    cell_values : array_like
        (m,) or (m, c) values per cell, in the order of the cells.
    method : {"volume", "l2"}
        ``"volume"``: volume-weighted average of the cells around each node (lumped L2 projection;
        monotone: the nodal values stay within the range of the cell values). ``"l2"``: consistent L2
        projection onto P1 (more accurate for smooth fields, may over/undershoot). Both keep the
        integral of the field exactly.
    axisymmetric : bool
        (r, z) cells (x = r): volumes of revolution 2 pi r_centroid |K| (the integral kept is the 3D one).

    Returns
    -------
    ndarray
        (n,) or (n, c) nodal values.

    Examples
    --------
    >>> pts = [[0., 0], [1, 0], [1, 1], [0, 1]]
    >>> cell_to_nodes(pts, [[0, 1, 2], [0, 2, 3]], [1.0, 3.0]).tolist()
    [2.0, 1.0, 2.0, 3.0]
    """
    pts, cells, dim = _as_arrays(points, cells)
    v = np.asarray(cell_values, dtype=float)
    vv = v[:, None] if v.ndim == 1 else v
    n = len(pts)
    vol = np.abs(signed_measure(pts, cells))
    if axisymmetric:
        vol = vol * (2 * np.pi * pts[cells, 0].mean(axis=1))
    npc = dim + 1
    rows = cells.ravel()
    if method == "volume":
        w = np.zeros(n)
        np.add.at(w, rows, np.repeat(vol, npc))
        acc = np.zeros((n, vv.shape[1]))
        np.add.at(acc, rows, np.repeat(vol[:, None] * vv, npc, axis=0))
        with np.errstate(invalid="ignore", divide="ignore"):
            out = np.where(w[:, None] > 0, acc / w[:, None], 0.0)
    elif method == "l2":
        from scipy.sparse import coo_matrix
        from scipy.sparse.linalg import cg

        local = (np.ones((npc, npc)) + np.eye(npc)) / ((npc) * (npc + 1))  # P1 mass / volume
        r = np.repeat(cells, npc, axis=1).ravel()
        c = np.tile(cells, (1, npc)).ravel()
        mass = coo_matrix(((vol[:, None, None] * local).ravel(), (r, c)), shape=(n, n)).tocsr()
        lumped = np.asarray(mass.sum(axis=1)).ravel()
        b = np.zeros((n, vv.shape[1]))
        np.add.at(b, rows, np.repeat(vol[:, None] * vv / npc, npc, axis=0))
        out = np.zeros_like(b)
        safe = np.where(lumped > 0, lumped, 1.0)
        for j in range(vv.shape[1]):  # the mass matrix is spectrally equivalent to its diagonal
            out[:, j], _ = cg(mass, b[:, j], x0=b[:, j] / safe, rtol=1e-12, maxiter=500, M=_diag(1 / safe))
    else:
        raise ValueError(f"unknown recovery method {method!r}; valid: volume, l2")
    return out[:, 0] if v.ndim == 1 else out


def _diag(d):
    from scipy.sparse import diags

    return diags(d)


def nodes_to_cells(cells, nodal_values):
    """Cell means of a P1 field (the average of its vertex values): (m,) or (m, c).

    >>> nodes_to_cells([[0, 1, 2]], [0.0, 1.0, 2.0]).tolist()
    [1.0]
    """
    cells = np.asarray(cells, dtype=np.int64)
    return np.asarray(nodal_values, dtype=float)[cells].mean(axis=1)


def transfer_cell(old_points, old_cells, cell_values, new_points, new_cells, method="volume", tol=1e-9,
                  axisymmetric=False):
    """Transfer a cell field: recover to nodes on the old mesh, interpolate, average on the new cells.

    Parameters
    ----------
    old_points, old_cells : array_like
        Old mesh (deformed coordinates when the body moved).
    cell_values : array_like
        (m_old,) or (m_old, c) values per old cell (e.g. ``p``, or ``epsp`` in Mandel notation).
    new_points, new_cells : array_like
        New mesh.
    method : {"volume", "l2"}
        Recovery, see :func:`cell_to_nodes`.

    Onto the identical mesh (same cells, same coordinates) the field is returned unchanged: recovery
    and averaging would smooth it.

    Returns
    -------
    values_new : ndarray
        (m_new,) or (m_new, c) values per new cell.
    n_outside : int
        New nodes outside the old mesh (see the module policy).

    Examples
    --------
    >>> pts = [[0., 0], [1, 0], [1, 1], [0, 1]]
    >>> tri = [[0, 1, 2], [0, 2, 3]]
    >>> v, out = transfer_cell(pts, tri, [1.0, 1.0], pts, [[0, 1, 3], [1, 2, 3]])
    >>> v.tolist(), out
    ([1.0, 1.0], 0)
    """
    if _same_mesh(old_points, old_cells, new_points, new_cells):
        return np.array(cell_values, dtype=float), 0
    nodal = cell_to_nodes(old_points, old_cells, cell_values, method, axisymmetric)
    new_nodal, n_outside = transfer_nodal(old_points, old_cells, nodal, new_points, tol)
    return nodes_to_cells(new_cells, new_nodal), n_outside


def _same_mesh(old_points, old_cells, new_points, new_cells):
    a, b = np.asarray(old_cells), np.asarray(new_cells)
    if a.shape != b.shape or not np.array_equal(a, b):
        return False
    x, y = np.asarray(old_points, dtype=float), np.asarray(new_points, dtype=float)
    d = a.shape[1] - 1
    x, y = x.reshape(-1, d) if x.ndim == 1 else x[:, :d], y.reshape(-1, d) if y.ndim == 1 else y[:, :d]
    return x.shape == y.shape and np.array_equal(x, y)


def transfer_active_set(old_points, old_cells, active, new_points, candidates=None, tol=1e-9):
    """Initial guess of the contact active set on the new mesh.

    The 0/1 nodal indicator of the old active set is interpolated and thresholded at 1/2; with
    ``candidates`` (a boolean mask of the new nodes that can touch, e.g. the contact boundary) the
    other nodes are inactive. Returns ``(active_new (p,) bool, n_outside)``.

    >>> act, out = transfer_active_set([[0., 0], [1, 0], [0, 1]], [[0, 1, 2]], [1, 1, 0], [[0.5, 0], [0, 0.9]])
    >>> act.tolist(), out
    ([True, False], 0)
    """
    ind, n_outside = transfer_nodal(old_points, old_cells, np.asarray(active, dtype=float), new_points, tol)
    act = ind >= 0.5
    if candidates is not None:
        act &= np.asarray(candidates, dtype=bool)
    return act, n_outside
