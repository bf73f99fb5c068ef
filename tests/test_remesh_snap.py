"""New boundary nodes out of a 2D polygon tool after a remesh (``remesh.snap_to_tool``, wendel.remesh.snap).

The new boundary nodes lie on the old boundary polygon; where an old edge's two nodes stand outside a rounded
tool corner but the edge passes through it, the finer new nodes on that edge are inside the tool (measured on
the F-bar steel cut, issue 17: 1.3-3.4 um deep at every remesh, behind a 20 um edge radius)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from wendel.remesh import mesher, quality, snap
from wendel.results import separation, vtu

from test_remesh_cut import _square

# a diamond standing on a rounded corner: (0.5, 1) and (1, 1), the old top nodes, are outside it, the old top
# edge between them passes 0.0586 deep through its arc (lowest point 0.9 + 0.1 sqrt 2 - 0.1)
DIAMOND = np.array([[0.75, 0.9], [1.25, 1.4], [0.75, 1.9], [0.25, 1.4]])
RADII = [0.1, 0.0, 0.0, 0.0]


def _coarse_square(tmp_path):
    pts, tris, lines = _square(2)       # the unit square of 2 x 2 cells: top edges 0.5 long
    path = tmp_path / "square.msh"
    names = {(1, 1): "left", (2, 1): "right", (3, 1): "bottom", (4, 1): "top", (100, 2): "domain"}
    separation.write_msh(path, pts, tris, [100] * len(tris), [e for e, _ in lines], [lab for _, lab in lines],
                         np.zeros((0, 2), dtype=np.int64), names)
    return path, pts


def test_nodes_on_an_edge_through_the_tool_go_onto_its_surface(tmp_path):
    path, pts = _coarse_square(tmp_path)
    assert not snap.inside(pts, DIAMOND, RADII).any()          # the old nodes are all outside the tool
    new = tmp_path / "new.msh"
    mesher.remesh(pts, path, new, 0.04)
    Y, cells = vtu.read_mesh(new, 2)
    Y = Y[:, :2]
    boundary = np.unique(mesher.boundary_facets(cells))
    inside = snap.inside(Y[boundary], DIAMOND, RADII)
    _, depth = snap.closest(Y[boundary][inside], DIAMOND, RADII)
    assert inside.sum() >= 3 and depth.max() > 0.04           # the new top nodes under the arc are inside it

    moved, rep = snap.onto_tool(new, Y.copy(), cells, {"vertices": DIAMOND, "radii": RADII})
    assert rep["tool_snapped_nodes"] == inside.sum() and rep["tool_snap_scale"] == 1.0
    assert abs(rep["tool_snap_max"] - depth.max()) < 1e-12
    on, gap = snap.closest(moved[boundary][inside], DIAMOND, RADII)
    assert gap.max() < 1e-12                                   # now on the tool's surface (arc or sides) ...
    assert np.all(moved[boundary][inside][:, 1] < Y[boundary][inside][:, 1])   # ... out of it, downwards
    assert np.all(quality.signed_measure(np.hstack([moved, 0 * moved[:, :1]]), cells) > 0)
    far = np.linalg.norm(Y - [0.75, 1.0], axis=1) > 0.4
    assert np.array_equal(moved[far], Y[far])                  # the move stays near the tool
    interior = np.setdiff1d(np.arange(len(Y)), boundary)
    assert np.abs(moved[interior] - Y[interior]).max() > 0     # interior nodes follow (no sliver cells)
    again, _ = vtu.read_mesh(new, 2)                           # the file holds the moved nodes, same cells
    assert np.array_equal(again[:, :2], moved) and np.array_equal(vtu.read_mesh(new, 2)[1], cells)
    assert mesher.read_mesh(new)[5].tolist() == mesher.read_mesh(tmp_path / "new.msh")[5].tolist()


def test_nothing_moves_without_a_node_inside(tmp_path):
    path, pts = _coarse_square(tmp_path)
    new = tmp_path / "new.msh"
    mesher.remesh(pts, path, new, 0.04)
    before = new.read_bytes()
    Y, cells = vtu.read_mesh(new, 2)
    lifted = DIAMOND + [0.0, 0.2]                              # the arc's lowest point at 1.14: above the body
    moved, rep = snap.onto_tool(new, Y[:, :2], cells, {"vertices": lifted, "radii": RADII})
    assert rep["tool_snapped_nodes"] == 0 and np.array_equal(moved, Y[:, :2]) and new.read_bytes() == before


def test_a_cut_snaps_at_its_remeshes(tmp_path):
    """The FE cut's remeshes with ``cutting.snap_to_tool``: every new mesh's boundary nodes are out of the tool
    where it stood (to 1e-9 of the edge radius), and the remesh reports say how many moved."""
    from test_cutting_fe import STEEL

    from wendel.cutting.fe_run import run_cut
    from wendel.scene import load

    scene = load(STEEL, smoke=True)
    scene.cutting.snap_to_tool = True
    scene.cutting.remesh_every = 2
    root = run_cut(scene, STEEL, tmp_path / "cut", smoke=True, progress=lambda *_: None, frames=False)
    tool = json.loads((root / "scene.resolved.json").read_text())["contact"]["tool"]
    reports = sorted((root / "remesh").glob("remesh-*.json"))
    assert len(reports) >= 1
    for f in reports:
        r = json.loads(f.read_text())
        assert "tool_snapped_nodes" in r and r["tool_snap_scale"] == 1.0
        rec = json.loads((root / "fem" / f"inc-{r['after_increment']:04d}" / "record.json").read_text())
        v = np.array(tool["vertices"]) + [rec["tool_x"], rec["tool_y"]]
        Y, cells = vtu.read_mesh(root / "meshes" / f"mesh-{r['remesh']}.msh", 2)
        b = Y[np.unique(mesher.boundary_facets(cells)), :2]
        ins = snap.inside(b, v, tool["radii"])
        assert not ins.any() or snap.closest(b[ins], v, tool["radii"])[1].max() < 1e-9 * tool["radii"][1]


_SNAP = "\n[remesh]\nsnap_to_tool = true\n"
_TOOL = "radii = [0.5, 0.0, 0.0] }"
_PATH = "y = [0.0, -0.01, -0.01] }"
SNAP_REFUSED = [
    ("hertz.toml", ("[loading]", "[loading]"),
     "remesh.snap_to_tool needs a 2D polygon tool (contact.obstacle = \"tool\" with contact.tool.vertices)"),
    ("scratch.toml", ("1.4226497308103742], [-2.598", "1.4226497308103742], [0.0, 1.0], [-2.598"),
     "remesh.snap_to_tool handles convex tools; contact.tool.vertices[2] is a reflex corner"),
    ("scratch.toml", (_PATH, "y = [0.0, -0.01, -0.01], angle = [0.0, 0.0, 5.0] }"),
     "remesh.snap_to_tool is for a tool that only translates; contact.path.angle turns it"),
]


@pytest.mark.parametrize("scene,change,words", SNAP_REFUSED, ids=["no polygon tool", "reflex corner", "turned tool"])
def test_a_snap_it_cannot_make_is_refused_by_key(scene_file, scene, change, words):
    """``remesh.snap_to_tool`` where :mod:`wendel.remesh.snap` would do nothing or the wrong thing (no polygon
    tool, a concave one, a turned one): the scene is refused naming the file and the key, not run unsnapped."""
    from conftest import WORKFLOWS, edit

    from wendel.scene import SceneError, load

    text = edit((WORKFLOWS / scene).read_text(), *change)
    if "reflex" in words:
        text = edit(text, _TOOL, "radii = [0.5, 0.0, 0.0, 0.0] }")
    path = scene_file(text + _SNAP)
    with pytest.raises(SceneError) as exc:
        load(path)
    assert str(path) in str(exc.value) and words in str(exc.value)
    load(scene_file((WORKFLOWS / scene).read_text() + ("" if scene == "hertz.toml" else _SNAP), "ok.toml"))
