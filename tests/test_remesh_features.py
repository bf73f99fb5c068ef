"""2D remeshing with ``remesh.smooth_features``: a notch of the boundary below the new mesh's size is filled
before gmsh meshes it (wendel.remesh.features; measured on the F-bar cut, issue 17: a folded chip front pinned
corners a few um apart and gmsh's fresh meshes had quality 0.08-0.16, below the remesh threshold of 0.1)."""

from __future__ import annotations

import numpy as np

from wendel.remesh import features, mesher
from wendel.results import separation

from test_remesh_cut import _square


def _notched(tmp_path):
    """The unit square of 10 x 10 cells, its top side notched: a V 0.02 wide and 0.05 deep at x = 0.5."""
    n = 10
    pts, tris, lines = _square(n)
    path = tmp_path / "square.msh"
    names = {(1, 1): "left", (2, 1): "right", (3, 1): "bottom", (4, 1): "top", (100, 2): "domain"}
    separation.write_msh(path, pts, tris, [100] * len(tris), [e for e, _ in lines], [lab for _, lab in lines],
                         np.zeros((0, 2), dtype=np.int64), names)
    x = pts.copy()
    top = lambda i: i * (n + 1) + n
    x[top(4), 0], x[top(6), 0], x[top(5), 1] = 0.49, 0.51, 0.95
    return path, x


def test_a_notch_below_the_size_is_filled(tmp_path):
    path, x = _notched(tmp_path)
    plain = mesher.remesh(x, path, tmp_path / "plain.msh", 0.25)
    smooth = mesher.remesh(x, path, tmp_path / "smooth.msh", 0.25, smooth_features=0.25)
    assert plain["min_sicn"] < 0.3                # gmsh fills the notch's three corners with slivers
    assert smooth["min_sicn"] > 0.8
    assert smooth["boundary_labels"] == plain["boundary_labels"] == [1, 2, 3, 4]
    assert smooth["boundary_nodes_smoothed"] > 0 and plain["boundary_nodes_smoothed"] == 0
    # the notch is filled (its area 0.02 * 0.05 / 2), the square's corners stay
    assert abs(smooth["measure_new"] - smooth["measure_old"] - 0.0005) < 1e-9
    assert abs(smooth["measure_new"] - 1.0) < 1e-9


def test_the_drop_stays_within_the_share_of_the_size():
    """No node goes whose neighbours are a size apart or more, and none farther than the share off the new
    polygon; label changes stay."""
    path_pts = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.4], [1.0, 0.6], [1.0, 1.0], [0.0, 1.0]])
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 4], [4, 5], [5, 0]])
    labels = np.array([3, 2, 2, 2, 4, 1])
    # the straight right side: its inner nodes go only where their neighbours are closer than the size
    assert features.smooth(path_pts, edges, labels, np.full(6, 0.5), 0.25)[0].tolist() == edges.tolist()
    out, lab = features.smooth(path_pts, edges, labels, np.full(6, 0.7), 0.25)
    assert sorted(set(out.ravel().tolist())) == [0, 1, 3, 4, 5] and lab.tolist() == [3, 2, 2, 4, 1]
    bent = path_pts.copy()
    bent[3, 0] = 0.8                      # 0.2 off the chord of its neighbours: more than 0.25 of 0.7
    assert 3 in set(features.smooth(bent, edges, labels, np.full(6, 0.7), 0.25)[0].ravel().tolist())
