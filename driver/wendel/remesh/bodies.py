"""2D remeshing of several bodies and of bodies cut along opened faces (a DG separation, ``separated.msh``).

A mesh cut along opened faces (boundary ``opened``, :mod:`wendel.results.separation`) has its vertices doubled
along the cut: its two sides are two boundary curves at the same place. gmsh's 2D meshers start from a
triangulation of the boundary points of a surface, and two boundary curves on top of each other (the two sides
of a slit that opened only partly, or of a crack branch inside one body: measured on the notched plate, every
body has some) leave it no valid start: the lead's attempt had not finished after 10 minutes. So the cut is
meshed the other way round:

1. :func:`glue` merges the copies of each doubled vertex again (same reference position; the deformed
   position is the mean of the copies), so the cut faces are interior edges of one uncut mesh;
2. :func:`model_2d` builds one plane surface per body of that mesh (the loop of positive signed area is the
   outer boundary, the others holes) and the cut as discrete curves embedded in it (label ``opened``): gmsh
   meshes it with element edges along the cut;
3. :func:`wendel.results.separation.cut` opens the new mesh along the edges of the embedded curves again (the
   same vertex doubling as ``separated.msh``), and both sides become the boundary ``opened``.

The bodies of the new mesh are those of the old one; a crack that opened only partly keeps its tip.

>>> import numpy as np
>>> body_index(np.array([[0, 1, 2], [1, 3, 2], [4, 5, 6]])).tolist()
[0, 0, 1]
"""

from __future__ import annotations

import numpy as np

from ..results.separation import edge_owners


def components(faces: np.ndarray, labels: np.ndarray | None = None) -> np.ndarray:
    """Connected components of triangles (cells, or boundary faces of a 3D mesh) through shared edges, joined only
    where the two triangles have the same label (all alike without ``labels``): a component index per triangle."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    faces = np.asarray(faces)
    labels = np.ones(len(faces), dtype=np.int64) if labels is None else np.asarray(labels)
    edges = np.concatenate([np.sort(faces[:, [i, j]], axis=1) for i, j in ((0, 1), (1, 2), (2, 0))])
    owner = np.tile(np.arange(len(faces)), 3)
    _, eid = np.unique(edges, axis=0, return_inverse=True)
    eid = eid.ravel()
    order = np.argsort(eid, kind="stable")
    e_sorted, f_sorted = eid[order], owner[order]
    same = e_sorted[1:] == e_sorted[:-1]
    a, b = f_sorted[:-1][same], f_sorted[1:][same]
    keep = labels[a] == labels[b]
    a, b = a[keep], b[keep]
    g = coo_matrix((np.ones(len(a)), (a, b)), shape=(len(faces), len(faces)))
    return connected_components(g, directed=False)[1]


def body_index(cells: np.ndarray) -> np.ndarray:
    """Connected components of triangles through shared edges (vertex indices): a body index per cell, numbered
    in the order of their first cell."""
    first = {}
    return np.array([first.setdefault(int(v), len(first)) for v in components(cells)], dtype=np.int64)


def _area(pts, ring):
    x, y = pts[ring, 0], pts[ring, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def glue(points, cells, facets, facet_tags, label):
    """Merge the copies of the vertices on the facets labelled ``label`` that share their reference position.

    Returns ``(rep, cut)``: the representative of every vertex (itself if not merged) and the cut edges
    (sorted pairs of representatives, unique) that are interior edges once glued; the others (a side whose
    other side is not in the mesh) stay boundary edges labelled ``label``."""
    rep = np.arange(len(points))
    on = np.unique(facets[facet_tags == label])
    if len(on) == 0:
        return rep, np.zeros((0, 2), dtype=np.int64)
    _, first, inverse = np.unique(points[on, :2], axis=0, return_index=True, return_inverse=True)
    rep[on] = on[first[inverse.ravel()]]
    cut = np.unique(np.sort(rep[facets[facet_tags == label]], axis=1), axis=0)
    owners = edge_owners(rep[np.asarray(cells)])
    return rep, cut[np.array([len(owners.get(tuple(e), ())) == 2 for e in cut.tolist()], dtype=bool).reshape(-1)]


def model_2d(gmsh, pts, cells, edges, labels, feature_angle, groups, chains_2d, loops_of, cut=None, cut_label=0):
    """The gmsh model of every body (one surface each) with the ``cut`` edges embedded; returns the surface tags.

    ``edges``/``labels``: the outward boundary edges of all cells and their physical tags; ``groups`` collects
    the curve tags per tag; ``chains_2d`` and ``loops_of`` are the mesher's chain and loop builders; ``cut``:
    interior edges (vertex pairs) meshed as embedded curves of the physical tag ``cut_label``.
    """
    body = body_index(cells)
    edge_body = _edge_body(cells, body, edges)
    cut = np.zeros((0, 2), dtype=np.int64) if cut is None else np.asarray(cut, dtype=np.int64)
    cut_chains = _cut_chains(cut, set(np.unique(edges).tolist()), pts[:, :2], feature_angle)
    ends = {n for _, nodes in cut_chains for n in (nodes[0], nodes[-1])}
    surfaces, next_curve = [], [1]
    points_done: set[int] = set()
    for b in range(int(body.max()) + 1):
        sel = edge_body == b
        e, lab = edges[sel], labels[sel]
        chains = chains_2d(pts[:, :2], e.tolist(), lab, feature_angle, ends)
        tags = _add_curves(gmsh, pts, chains, groups, next_curve, points_done)
        loops = loops_of(chains)
        rings = [np.concatenate([chains[j][1][:-1] for j in lp]) for lp in loops]
        outer = [k for k, r in enumerate(rings) if _area(pts, r) > 0]
        if len(outer) != 1:
            raise ValueError(f"body {b}: {len(outer)} boundary loops run counter-clockwise (one outer boundary "
                             "expected): the old mesh is not a set of positively oriented planar bodies")
        order = outer + [k for k in range(len(loops)) if k != outer[0]]
        surfaces.append([[tags[j] for j in loops[k]] for k in order])
    cut_tags = _add_curves(gmsh, pts, [(cut_label, nodes) for _, nodes in cut_chains], groups, next_curve,
                           points_done)
    gmsh.model.mesh.createGeometry()
    out = [gmsh.model.geo.addPlaneSurface([gmsh.model.geo.addCurveLoop(w) for w in wires]) for wires in surfaces]
    gmsh.model.geo.synchronize()
    if len(cut):
        owners = edge_owners(np.asarray(cells))
        for (a, _b), tag in zip([(nodes[0], nodes[1]) for _, nodes in cut_chains], cut_tags):
            b = body[owners[(min(a, _b), max(a, _b))][0]]       # both cells of a cut edge are in one body
            gmsh.model.mesh.embed(1, [tag], 2, out[b])
    return out


def _cut_chains(cut, boundary_nodes, points, feature_angle):
    """Split the cut edges (undirected) into chains between their junctions, ends, boundary nodes and kinks
    (a turn by more than ``feature_angle`` degrees): ``[(0, [n0, ..., nk]), ...]``; a closed loop of cut
    edges starts at its first node."""
    nbr: dict[int, list[int]] = {}
    for a, b in cut.tolist():
        nbr.setdefault(a, []).append(b)
        nbr.setdefault(b, []).append(a)
    cos_max = np.cos(np.radians(feature_angle))

    def kink(n, ns):
        t1, t2 = points[n] - points[ns[0]], points[ns[1]] - points[n]
        return np.dot(t1, t2) < cos_max * np.linalg.norm(t1) * np.linalg.norm(t2)

    corners = {n for n, ns in nbr.items() if len(ns) != 2 or n in boundary_nodes or kink(n, ns)}
    used: set[tuple[int, int]] = set()
    chains = []

    def walk(a, b):
        nodes = [a, b]
        used.add((min(a, b), max(a, b)))
        while b not in corners:
            c = next((c for c in nbr[b] if (min(b, c), max(b, c)) not in used), None)
            if c is None:
                break       # back at the start of a closed loop
            used.add((min(b, c), max(b, c)))
            nodes.append(c)
            b = c
        return nodes

    for start in sorted(corners):
        for b in nbr[start]:
            if (min(start, b), max(start, b)) not in used:
                chains.append((0, walk(start, b)))
    for a, b in cut.tolist():           # closed loops without a corner
        if (min(a, b), max(a, b)) not in used:
            corners.add(a)
            chains.append((0, walk(a, b)))
    return chains


def _edge_body(cells, body, edges):
    """The body of each boundary edge (the body of the cell it bounds; of a chord that replaced boundary edges,
    :mod:`wendel.remesh.features`, the body of its first node's cells)."""
    table, node = {}, {}
    for c, tri in enumerate(cells.tolist()):
        for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            table[(a, b)] = body[c]
            node[a] = body[c]
    return np.array([table[(a, b)] if (a, b) in table else node[a] for a, b in edges.tolist()], dtype=np.int64)


def _add_curves(gmsh, pts, chains, groups, next_curve, points_done):
    """Discrete points and curves of the chains (with their old nodes); returns the curve tag per chain."""
    tags = []
    for lab, nodes in chains:
        for node in (nodes[0], nodes[-1]):
            if node not in points_done:
                points_done.add(node)
                gmsh.model.addDiscreteEntity(0, node + 1)
                gmsh.model.mesh.addNodes(0, node + 1, [node + 1], pts[node].tolist())
        tag = next_curve[0]
        next_curve[0] += 1
        gmsh.model.addDiscreteEntity(1, tag, [nodes[0] + 1, nodes[-1] + 1])
        inner = np.asarray(nodes[1:-1], dtype=np.int64)
        if len(inner):
            gmsh.model.mesh.addNodes(1, tag, (inner + 1).tolist(), pts[inner].ravel().tolist())
        seg = np.column_stack([nodes[:-1], nodes[1:]]) + 1
        gmsh.model.mesh.addElementsByType(tag, 1, [], seg.ravel().tolist())
        groups[lab].append(tag)
        tags.append(tag)
    return tags




def inside_targets(points: np.ndarray, cells: np.ndarray, on: np.ndarray) -> np.ndarray:
    """The nodes ``points`` with those in ``on`` (nodes on a cut) moved 1e-3 of the way to the mean centroid of
    their own cells: located in the old mesh, whose cut lies where the new one's does, each side of the cut
    then finds its own side (its two copies of a node sit at the same place).

    >>> inside_targets(np.array([[0., 0], [1, 0], [0, 1]]), np.array([[0, 1, 2]]), np.array([0])).round(6).tolist()
    [[0.000333, 0.000333], [1.0, 0.0], [0.0, 1.0]]
    """
    if len(on) == 0:
        return points
    centre = np.zeros((len(points), points.shape[1]))
    count = np.zeros(len(points))
    c = points[cells].mean(axis=1)
    for k in range(cells.shape[1]):
        np.add.at(centre, cells[:, k], c)
        np.add.at(count, cells[:, k], 1.0)
    out = np.array(points, dtype=float)
    out[on] += 1e-3 * (centre[on] / count[on, None] - out[on])
    return out
