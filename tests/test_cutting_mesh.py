"""Orthogonal cutting, the graded mesh (issue 17): fine at the cutting edge, coarse far from it.

``cutting.edge_size`` makes :func:`wendel.cutting.fe.fe_scene` refine the first mesh at the edge (the
builder's ``refine``) and give the remeshes size zones that follow the tool (``remesh.zones``,
``zones_follow = "tool"``). On real gmsh meshes of the steel scene's workpiece: the first mesh and a remesh with
the tool moved 0.1 mm must have elements of the edge size at the edge, of the middle size over the primary
shear zone, and twice that far away."""

import json

import numpy as np
import pytest

from wendel.cutting.fe import FAR, fe_scene, tool_at_start
from wendel.scene.reading import SceneError
from wendel.meshes.cutting import orthogonal_cutting
from wendel.remesh import mesher
from wendel.remesh.step import zones_at
from wendel.scene import load

from conftest import WORKFLOWS

STEEL = WORKFLOWS / "cutting-aisi1045.toml"


def _longest_edges(path):
    p, _, cells, *_ = mesher.read_mesh(path)
    xy = p[:, :2]
    longest = np.max([np.linalg.norm(xy[cells[:, i]] - xy[cells[:, (i + 1) % 3]], axis=1) for i in range(3)], axis=0)
    return xy[cells].mean(axis=1), longest


def _near(centres, longest, point, radius):
    return longest[np.linalg.norm(centres - point, axis=1) < radius]


def test_graded_mesh_is_fine_at_the_edge_and_coarse_far_away(tmp_path):
    scene = load(STEEL)
    scene.cutting.edge_size = 5e-6             # m: r_edge / 4
    fe = fe_scene(scene)
    g = fe.geometry.model_extra
    r, s = scene.cutting.edge_radius * 1e3, 5e-3                          # mm
    h_mid = g["fine"] * fe.geometry.h
    assert fe.remesh.zones_follow == "tool" and fe.remesh.h == pytest.approx(FAR * h_mid)
    assert [z.h for z in fe.remesh.zones] == pytest.approx([s, h_mid])
    tip = np.array(tool_at_start(scene.cutting, g["length"] - g["pre_cut"])["tip"])
    built = orthogonal_cutting(tmp_path / "w.msh", h=fe.geometry.h,
                               **{k: g[k] for k in ("length", "depth", "uncut", "pre_cut", "fine", "refine")})
    c, longest = _longest_edges(built.path)
    corner = [g["length"] - g["pre_cut"], 0.0]                           # the step face's foot, the edge in front
    assert _near(c, longest, corner, r).max() < 1.5 * s                 # the first mesh: fine at the edge
    # a remesh with the tool moved 0.1 mm along its path (the record's placement): the zones move with it
    inc = tmp_path / "inc"
    inc.mkdir()
    (inc / "record.json").write_text(json.dumps({"tool_x": -0.1, "tool_y": 0.0}))
    zones = zones_at(fe.remesh, inc)
    assert zones[0]["box"][0][0] == pytest.approx(fe.remesh.zones[0].box[0][0] - 0.1)
    points = mesher.read_mesh(built.path)[0]
    info = mesher.remesh(points[:, :2], built.path, tmp_path / "r.msh", fe.remesh.h, zones=zones)
    c, longest = _longest_edges(tmp_path / "r.msh")
    edge = tip + [-0.1, r]
    assert _near(c, longest, edge, r).max() < 1.5 * s                   # the edge size at the moved edge
    assert np.median(_near(c, longest, edge + [-2 * 0.15, 0.1], 0.03)) == pytest.approx(h_mid, rel=0.35)
    far = longest[(c[:, 1] < -0.3) | (c[:, 0] < 0.5)]                     # the deep bulk and the layer far ahead
    assert np.median(far) == pytest.approx(FAR * h_mid, rel=0.3) and far.min() > 2 * s
    # cheaper than a uniform mesh at the middle size (about 4,400 elements on this body, measured)
    assert info["elements"] < 3500 and info["inverted"] == 0


def test_bad_zones_are_refused_with_the_key(tmp_path):
    text = STEEL.read_text().replace("remesh_every = 8 ", "edge_size = 0.2e-3\nremesh_every = 8 ")
    bad = tmp_path / "bad.toml"
    bad.write_text(text)
    with pytest.raises(SceneError, match="edge_size"):
        load(bad)
    with pytest.raises(ValueError, match="zones_follow"):
        fe = fe_scene(load(STEEL)).model_dump()
        fe["remesh"]["zones_follow"] = "tool"
        fe["contact"]["path"] = None
        type(fe_scene(load(STEEL))).model_validate(fe)


@pytest.mark.parametrize("name, var, value, words", [
    ("cutting-long", "WENDEL_BENCH_CUT_MM", "0.5",
     "WENDEL_BENCH_CUT_MM = 0.5: a length of cut in mm above 1.2 (cutting-steady's) and up to 20"),
    ("cutting-ti", "WENDEL_BENCH_CUT_MM", "0.1",
     "WENDEL_BENCH_CUT_MM = 0.1: a length of cut in mm from 0.4 (the scene's) to 20"),
    ("cutting-steady-fbar", "WENDEL_BENCH_CUT_MM", "25",
     "WENDEL_BENCH_CUT_MM = 25.0: a length of cut in mm above 1.2 (cutting-steady's) and up to 20"),
    ("cutting-steady-fbar", "WENDEL_BENCH_REMESH_EVERY", "six",
     "WENDEL_BENCH_REMESH_EVERY = 'six': a whole number of increments from 1 to 100"),
    ("cutting-steady", "WENDEL_BENCH_SNAP", "yes",
     "WENDEL_BENCH_SNAP = 'yes': 1 (cutting.snap_to_tool) or 0 (as the scene says)"),
    ("cutting-ti", "WENDEL_BENCH_SNAP", "2",
     "WENDEL_BENCH_SNAP = '2': 1 (cutting.snap_to_tool) or 0 (as the scene says)"),
    ("cutting-ti", "WENDEL_BENCH_STEADY_MEASURE", "raw",
     "WENDEL_BENCH_STEADY_MEASURE = 'raw': cycles (the default) or filtered"),
    ("cutting-steady-fbar", "WENDEL_BENCH_UNTIL_STEADY", "yes",
     "WENDEL_BENCH_UNTIL_STEADY = 'yes': 1 (cutting.stop_when_steady) or 0 (as the scene says)"),
    ("cutting-mesh", "WENDEL_BENCH_FBAR", "yes",
     "WENDEL_BENCH_FBAR = 'yes': 1 (cutting.volumetric = \"fbar\"), 0 (\"cell\") or unset (as the scene says)"),
    ("cutting-mesh", "WENDEL_BENCH_HEAT", "adiabatic",
     "WENDEL_BENCH_HEAT = 'adiabatic': isothermal (no Taylor-Quinney heat, thermal.beta = 0), conduction "
     "(thermal.coupling = \"staggered\") or unset (the scene's adiabatic heating)"),
    ("cutting-mesh", "WENDEL_BENCH_EDGES", "3,4",
     "WENDEL_BENCH_EDGES = '3,4': three different whole numbers from 2 to 8, the edge radius over the edge size "
     "(e.g. 3,4,5), and optionally one of them again, cut at half the step"),
    ("cutting-mesh", "WENDEL_BENCH_EDGES", "3,4,4",
     "WENDEL_BENCH_EDGES = '3,4,4': three different whole numbers from 2 to 8, the edge radius over the edge size "
     "(e.g. 3,4,5), and optionally one of them again, cut at half the step"),
    ("cutting-mesh", "WENDEL_BENCH_EDGES", "3,4,5,2",
     "WENDEL_BENCH_EDGES = '3,4,5,2': three different whole numbers from 2 to 8, the edge radius over the edge size "
     "(e.g. 3,4,5), and optionally one of them again, cut at half the step"),
    ("cutting-steady-fbar", "WENDEL_BENCH_EDGE", "1",
     "WENDEL_BENCH_EDGE = '1': a whole number from 2 to 8, the edge radius over the edge size"),
    ("cutting-kienzle", "WENDEL_BENCH_FBAR", "2",
     "WENDEL_BENCH_FBAR = '2': 1 (cutting.volumetric = \"fbar\"), 0 (\"cell\") or unset (as the scene says)"),
    ("cutting-paths", "WENDEL_BENCH_PATHS", "0",
     "WENDEL_BENCH_PATHS = '0': a whole number of paths from 1 to 20"),
    ("cutting-paths", "WENDEL_BENCH_BEFORE", "23",
     "WENDEL_BENCH_BEFORE = '23': one of 24, 25 (the loop before that session)"),
    ("cutting-paths", "WENDEL_BENCH_LEVER", "base",
     "WENDEL_BENCH_LEVER = 'base': one of newton_tol-1e-6, remesh_every-16, stages-converged, whole-first-step, "
     "lagged-softening, before-session-24, no-heat, sixteenth-first-step, 10-um-steps (cutting-levers' levers)"),
    ("cutting", "WENDEL_BENCH_CASES", "steel,brass",
     "WENDEL_BENCH_CASES = 'steel,brass': brass unknown; valid: steel, titanium"),
    ("cutting", "WENDEL_BENCH_RAKE", "45", "WENDEL_BENCH_RAKE = '45': a number from -20 to 30"),
    ("cutting", "WENDEL_BENCH_SPEED", "nan", "WENDEL_BENCH_SPEED = 'nan': a number from 20 to 1000"),
    ("cutting", "WENDEL_BENCH_FRICTION", "-0.1", "WENDEL_BENCH_FRICTION = '-0.1': a number from 0 to 2"),
])
def test_the_long_cut_benches_refuse_a_bad_setting_by_name_before_cutting(tmp_path, monkeypatch, name, var, value,
                                                                           words):
    from wendel.bench import BENCHES, _load_plugins
    _load_plugins()
    monkeypatch.setenv(var, value)
    with pytest.raises(ValueError) as err:
        BENCHES[name](False, tmp_path)
    assert str(err.value) == words
    assert not any(tmp_path.iterdir())          # nothing cut


def test_the_mesh_bench_takes_its_three_edges_from_the_environment(monkeypatch):
    from wendel.bench import edges
    from wendel.bench.cutting_mesh import CASES
    assert edges(CASES) == CASES
    monkeypatch.setenv("WENDEL_BENCH_EDGES", "5,3,4")
    assert edges(CASES) == [("r/3", 3, 1), ("r/5", 5, 1), ("r/4", 4, 1), ("r/3, half step", 3, 2)]
    monkeypatch.setenv("WENDEL_BENCH_EDGES", "3,4,5,4")
    assert edges(CASES)[3] == ("r/4, half step", 4, 2)


def test_the_steady_mesh_bench_neither_deletes_nor_reruns_an_unfinished_cut(tmp_path, monkeypatch):
    # session 22: the bench started while another process still wrote a finished cut's frames, took the folder for
    # a stale one, deleted it and cut again; now an unfinished folder is refused and left as it is
    from wendel.bench.cutting_mesh import _steady
    monkeypatch.setenv("WENDEL_BENCH_EDGE", "4")
    monkeypatch.setenv("WENDEL_BENCH_CONDUCTION", "1")
    busy = tmp_path / "r4-long-conduction"
    busy.mkdir()
    (busy / "history.csv").write_text("increment\n1\n")
    with pytest.raises(RuntimeError, match="unfinished cut"):
        _steady(False, tmp_path, "fbar", reuse=True)
    assert (busy / "history.csv").read_text() == "increment\n1\n"
