"""Remeshing a 2D mesh cut along opened faces (boundary ``opened``, a DG separation's ``separated.msh``): each
body is meshed anew, the cut stays cut (both sides ``opened``), a crack opened only partly keeps its tip
(wendel.remesh.bodies; before, gmsh did not finish meshing the coincident sides of a cut)."""

from __future__ import annotations

import meshio
import numpy as np
import pytest

from wendel.remesh import bodies, mesher
from wendel.results import separation


def _square(n=10):
    """The unit square, n x n cells of two triangles; boundary lines labelled left 1, right 2, bottom 3, top 4."""
    g = np.linspace(0.0, 1.0, n + 1)
    X, Y = np.meshgrid(g, g, indexing="ij")
    pts = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    idx = lambda i, j: i * (n + 1) + j
    tris = [t for i in range(n) for j in range(n)
            for t in ([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)], [idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)])]
    lines = [((idx(0, j + 1), idx(0, j)), 1) for j in range(n)] + [((idx(n, j), idx(n, j + 1)), 2) for j in range(n)]
    lines += [((idx(i, 0), idx(i + 1, 0)), 3) for i in range(n)] + [((idx(i + 1, n), idx(i, n)), 4) for i in range(n)]
    return pts, np.array(tris), lines


def _cut_square(tmp_path, edges_of):
    """The square cut along the edges ``edges_of(index)`` (pairs of grid vertices), written as a separated mesh."""
    n = 10
    pts, tris, lines = _square(n)
    cut = {tuple(sorted(e)) for e in edges_of(lambda i, j: i * (n + 1) + j)}
    p, t, opened, body = separation.cut(pts, tris, cut)
    names = {(1, 1): "left", (2, 1): "right", (3, 1): "bottom", (4, 1): "top", (100, 2): "domain"}
    path = tmp_path / "cut.msh"
    separation.write_msh(path, p, t, [100] * len(t), separation._renumber_lines(tris, t, [e for e, _ in lines]),
                         [lab for _, lab in lines], opened, names)
    return path, p, int(body.max()) + 1


def _opened(path):
    m = meshio.read(path, file_format="gmsh")
    tris = np.concatenate([c.data for c in m.cells if c.type == "triangle"])
    seg = np.concatenate([c.data[m.cell_data["gmsh:physical"][i] == 31] for i, c in enumerate(m.cells) if c.type == "line"])
    return m.points[:, :2], tris, seg


@pytest.mark.parametrize("case", ["two bodies", "partly opened"])
def test_a_mesh_cut_along_opened_faces_is_remeshed_body_by_body_and_stays_cut(tmp_path, case):
    if case == "two bodies":         # cut across at y = 0.5, with a branch into the upper body (a slit inside it)
        edges = lambda v: [(v(i, 5), v(i + 1, 5)) for i in range(10)] + [(v(4, 5), v(4, 6)), (v(4, 6), v(4, 7))]
        length, pieces = 1.0 + 0.2, 2
    else:                            # a crack from the left edge to the middle, its tip at (0.5, 0.3)
        edges = lambda v: [(v(i, 3), v(i + 1, 3)) for i in range(5)]
        length, pieces = 0.5, 1
    path, points, nb = _cut_square(tmp_path, edges)
    assert nb == pieces
    info = mesher.remesh(points[:, :2], path, tmp_path / "new.msh", 0.05)
    assert info["bodies"] == pieces and 31 in info["boundary_labels"] and info["inverted"] == 0
    assert info["measure_new"] == pytest.approx(1.0, rel=1e-12)
    assert info["elements"] > 2 * len(meshio.read(path).cells_dict["triangle"])        # h 0.1 -> 0.05
    p, tris, seg = _opened(tmp_path / "new.msh")
    # both sides of every cut face are boundary segments 'opened': the cut length is kept (straight cuts)
    assert np.linalg.norm(p[seg[:, 1]] - p[seg[:, 0]], axis=1).sum() / 2 == pytest.approx(length, rel=1e-12)
    edge_count = {}
    for t in tris.tolist():
        for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])):
            edge_count[tuple(sorted(e))] = edge_count.get(tuple(sorted(e)), 0) + 1
    assert all(edge_count[tuple(sorted(e))] == 1 for e in seg.tolist())
    e1, e2 = p[tris[:, 1]] - p[tris[:, 0]], p[tris[:, 2]] - p[tris[:, 0]]
    cell_area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    area = lambda k: cell_area[k]
    body = bodies.body_index(tris)
    if case == "two bodies":
        assert sorted(area(body == k).sum() for k in range(2)) == pytest.approx([0.5, 0.5], rel=1e-12)
    else:
        # the vertices on the crack are doubled except its tip; the tip is one vertex of the new mesh
        on = np.unique(seg)
        tip = np.flatnonzero(np.all(np.isclose(p[on], [0.5, 0.3]), axis=1))
        assert len(tip) == 1
        others = p[on][np.abs(p[on][:, 0] - 0.5) > 1e-9]
        assert len(others) == 2 * len(np.unique(others.round(12), axis=0))


def test_the_pieces_no_boundary_condition_holds_are_left_out(tmp_path):
    # cut across at y = 0.5 and around the cell [0.7, 0.8] x [0.7, 0.8] (an island of two triangles)
    island = lambda v: [(v(7, 7), v(8, 7)), (v(8, 7), v(8, 8)), (v(8, 8), v(7, 8)), (v(7, 8), v(7, 7))]
    path, points, nb = _cut_square(tmp_path, lambda v: [(v(i, 5), v(i + 1, 5)) for i in range(10)] + island(v))
    assert nb == 3
    keep, used = separation.keep_held(path, tmp_path / "held.msh", {3, 4})      # bottom and top hold
    assert keep.sum() == 200 - 2 and len(used) == len(points) - 4
    p, tris, seg = _opened(tmp_path / "held.msh")
    assert bodies.body_index(tris).max() + 1 == 2 and len(p) == len(used)
    assert len(seg) == 2 * 10 + 4           # both sides of the cut across, the island's outside only
    info = mesher.remesh(p, tmp_path / "held.msh", tmp_path / "new.msh", 0.1)
    assert info["bodies"] == 2 and info["measure_new"] == pytest.approx(0.99, rel=1e-12)
