"""2D remeshing: boundary features below the new mesh's resolution smoothed away (``remesh.smooth_features``).

The 2D remesher keeps every old boundary node where the boundary turns by more than the feature angle as a node
of the new mesh (a corner). A free surface that wrinkles or folds on a scale below the new mesh's size (measured
on the F-bar cut, issue 17: the concave corner where the chip's front meets the uncut surface ahead of it folds
into a notch 3-5 um deep, 0.4 mm ahead of the tool where the new mesh is 25 um) then pins a group of corners a few
microns apart, and gmsh has to fill them with slivers: minimum quality 0.09-0.096 straight out of gmsh, below the
remesh threshold of 0.1, so the cut was remeshed after every increment from 720 um on.

:func:`smooth` drops such nodes from the boundary polygon before gmsh sees it: a node whose two boundary
neighbours are closer than the local target size ``s`` (the new mesh could not place a node between them anyway)
and which stands less than ``feature * s`` off their chord, as do the nodes dropped before between them (so the
old polygon's nodes stay within ``feature * s`` of the new one). The node whose drop changes the area least goes
first (Visvalingam and Whyatt's order: the tip of a notch before its sides), and its neighbours are judged again. Nodes where the boundary label changes and non-manifold nodes stay, and a chord that
would cross another boundary edge is not taken. The domain changes by the small triangles cut off or added
(less than ``feature * s`` deep each); new nodes outside the old mesh get the nearest old boundary values
(:mod:`wendel.remesh.transfer`).

>>> import numpy as np
>>> pts = np.array([[0., 0], [1, 0], [1.02, 0.5], [1, 1], [0, 1]])   # a 0.02 kink on the right side
>>> e = np.array([[0, 1], [1, 2], [2, 3], [3, 4], [4, 0]])
>>> out, lab = smooth(pts, e, np.zeros(5, dtype=int), np.full(5, 1.5), 0.1)
>>> out.tolist()
[[0, 1], [1, 3], [3, 4], [4, 0]]
>>> smooth(pts, e, np.zeros(5, dtype=int), np.full(5, 0.9), 0.1)[0].tolist() == e.tolist()   # chord 1 > s
True
"""

from __future__ import annotations

import heapq

import numpy as np

__all__ = ["indicator_size", "smooth", "target_size"]


def indicator_size(h: float, h_min: float, size_indicator, n: int) -> np.ndarray:
    """The size the nodal ``size_indicator`` asks for at each of the ``n`` nodes: ``h`` where it is 0, ``h_min``
    at its maximum, linear in between (``h`` everywhere when its maximum is not positive); the remesher's
    PostView field (:func:`wendel.remesh.mesher.remesh`).

    >>> indicator_size(4.0, 1.0, [0.0, 1.0, 2.0], 3).tolist()
    [4.0, 2.5, 1.0]
    """
    ind = np.asarray(size_indicator, dtype=float).reshape(n)
    top = ind.max() if n else 0.0
    t = np.clip(ind / top, 0.0, 1.0) if top > 0 else np.zeros(n)
    return h + (h_min - h) * t


def target_size(points: np.ndarray, h: float, size_indicator=None, h_min: float | None = None,
                zones=None) -> np.ndarray:
    """The remesher's target size at ``points`` (n, 2|3): ``h``, the indicator's linear size (``h`` at 0,
    ``h_min`` at its maximum) and the zones (gmsh Box fields: ``h`` inside the box, linear to the outer size over
    ``thickness`` outside it), the smallest holding (:func:`wendel.remesh.mesher.remesh`).

    >>> target_size(np.array([[0., 0], [2, 0], [5, 0]]), 4.0, zones=[{"box": [[-1, -1], [1, 1]], "h": 1.0,
    ...                                                                "thickness": 2.0}]).tolist()
    [1.0, 2.5, 4.0]
    """
    points = np.asarray(points, dtype=float)
    s = np.full(len(points), float(h))
    if size_indicator is not None:
        s = np.minimum(s, indicator_size(h, h / 4 if h_min is None else h_min, size_indicator, len(points)))
    for z in zones or []:
        lo, hi = (np.asarray(c, dtype=float) for c in z["box"])
        d = len(lo)
        gap = np.maximum(np.maximum(lo - points[:, :d], points[:, :d] - hi), 0.0)
        dist = np.sqrt((gap ** 2).sum(axis=1))
        t = float(z.get("thickness", 0.0))
        inner = float(z["h"])
        zs = np.where(dist <= 0, inner, np.where(dist < t, inner + (h - inner) * dist / max(t, 1e-300), h))
        s = np.minimum(s, zs)
    return s


def _crosses(p, q, a, b) -> np.ndarray:
    """Whether segment p-q properly crosses each segment a[i]-b[i] (shared end points do not count)."""
    def orient(u, v, w):
        return (v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0])
    d1, d2 = orient(a, b, p), orient(a, b, q)
    d3, d4 = orient(p, q, a), orient(p, q, b)
    return (d1 * d2 < 0) & (d3 * d4 < 0)


def smooth(points: np.ndarray, edges: np.ndarray, labels: np.ndarray, size: np.ndarray, feature: float):
    """The boundary ``edges`` (oriented, (m, 2)) with nodes of sub-resolution features dropped (see the module):
    ``(edges, labels)``, the dropped nodes' two edges replaced by their chord with the same label. ``size``: the
    target size at every node; ``feature``: the largest deviation from the chord, as a share of it."""
    edges = np.asarray(edges, dtype=np.int64)
    labels = np.asarray(labels)
    if feature <= 0 or len(edges) == 0:
        return edges, labels
    pts = np.asarray(points, dtype=float)[:, :2]
    nxt, prv, lab_out, lab_in = {}, {}, {}, {}
    degree_out, degree_in = {}, {}
    for (a, b), lab in zip(edges.tolist(), labels.tolist()):
        nxt[a], prv[b] = b, a
        lab_out[a], lab_in[b] = lab, lab
        degree_out[a] = degree_out.get(a, 0) + 1
        degree_in[b] = degree_in.get(b, 0) + 1
    fixed = {n for n in set(degree_out) | set(degree_in)
             if degree_out.get(n, 0) != 1 or degree_in.get(n, 0) != 1 or lab_out.get(n) != lab_in.get(n)}
    removed: set[int] = set()
    hidden: dict[int, list[int]] = {}       # the dropped nodes of the edge that starts at a node

    def score(n):
        """The area of the triangle ``n`` and its neighbours, or None when ``n`` may not go: every node the chord
        would replace (``n`` and those its two edges replace already) within ``feature`` times the size at ``n``
        of it."""
        if n in fixed or n in removed:
            return None
        p, q = prv[n], nxt[n]
        if p == q or nxt.get(q) == p:       # a loop of three nodes stays
            return None
        chord = pts[q] - pts[p]
        c2 = float(chord @ chord)
        if c2 >= size[n] ** 2 or c2 <= 0:
            return None
        under = pts[hidden.get(p, []) + [n] + hidden.get(n, [])] - pts[p]
        t = np.clip(under @ chord / c2, 0.0, 1.0)
        dev = float(np.sqrt(((under - t[:, None] * chord) ** 2).sum(axis=1)).max())
        if dev >= feature * size[n]:
            return None
        e = pts[n] - pts[p]
        return 0.5 * abs(chord[0] * e[1] - chord[1] * e[0])     # the area the drop changes: least first

    heap = [(sc, n, p_, q_) for n in nxt if (sc := score(n)) is not None for p_, q_ in [(prv[n], nxt[n])]]
    heapq.heapify(heap)
    while heap:
        _, n, p, q = heapq.heappop(heap)
        if n in removed or prv.get(n) != p or nxt.get(n) != q:
            continue                        # stale: its neighbours changed since it was scored
        if score(n) is None:
            continue
        live = np.array([(a, nxt[a]) for a in nxt if a not in removed and a not in (p, n)
                         and nxt[a] not in (p, n, q) and a != q], dtype=np.int64).reshape(-1, 2)
        if len(live) and _crosses(pts[p], pts[q], pts[live[:, 0]], pts[live[:, 1]]).any():
            continue
        removed.add(n)
        hidden[p] = hidden.get(p, []) + [n] + hidden.pop(n, [])
        nxt[p], prv[q] = q, p
        del nxt[n], prv[n]
        for m in (p, q):
            sc = score(m)
            if sc is not None:
                heapq.heappush(heap, (sc, m, prv[m], nxt[m]))
    if not removed:
        return edges, labels
    out = [(a, b) for a, b in nxt.items()]
    return np.array(out, dtype=np.int64), np.array([lab_out[a] for a, _ in out], dtype=labels.dtype)
