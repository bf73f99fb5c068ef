"""Drilling: material removal by geometry (meshes/drilling.py) and the process loop (wendel.drilling)."""

from __future__ import annotations

import json
import math

import meshio
import numpy as np
import pytest

from wendel.meshes import LABELS
from wendel.meshes import drilling as D
from wendel.remesh.step import cell_volumes

from conftest import IRON, IRON_THERMAL, drill, drill_table

R, DIA, ANGLE = 0.003, 0.006, 118.0


def _facet_labels(mesh, kind):
    return set(np.unique(mesh.cell_data_dict["gmsh:physical"][kind]).tolist())


@pytest.mark.parametrize("depth", [0.001, 0.004, 0.012])
def test_removed_volume_3d_block(tmp_path, depth):
    """Block minus the bore: the removed volume equals V(d) within the chord error of the meshed circle."""
    h_bore = 0.0008
    b = D.drilled(tmp_path / "m.msh", "block", depth=depth, diameter=DIA, point_angle=ANGLE,
                  x=(-0.012, 0.012), y=(-0.012, 0.012), height=0.02, h=0.003, h_bore=h_bore)
    m = meshio.read(b.path)
    removed = 0.024 * 0.024 * 0.02 - cell_volumes(m.points, m.cells_dict["tetra"]).sum()
    exact = D.bore_volume(depth, R, ANGLE)
    # an inscribed polygon of side h misses (h/r)^2/6 of a disc of radius r (the wetted radius of the
    # cone while the shoulder is not in); allow three times that
    r_wet = min(R, depth * math.tan(math.radians(ANGLE) / 2))
    assert abs(removed - exact) <= exact * (h_bore / r_wet) ** 2 / 2
    assert removed <= exact * (1 + 1e-9)
    labels = _facet_labels(m, "triangle")
    assert LABELS["bore_bottom"] in labels and LABELS["top"] in labels
    assert (LABELS["bore_wall"] in labels) == (depth > D.cone_height(R, ANGLE))


def test_bore_areas_on_the_mesh(tmp_path):
    """The re-tagged bore wall and bottom have the areas of the analytic bore (chord error)."""
    depth = 0.01
    b = D.drilled(tmp_path / "m.msh", "cylinder", depth=depth, diameter=DIA, radius=0.012, height=0.02,
                  h=0.003, h_bore=0.0006)
    m = meshio.read(b.path)
    tags = m.cell_data_dict["gmsh:physical"]["triangle"]
    tri = m.cells_dict["triangle"]
    p = m.points
    area = 0.5 * np.linalg.norm(np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]), axis=1)
    wall, bottom = D.bore_areas(depth, R, ANGLE)
    assert area[tags == LABELS["bore_wall"]].sum() == pytest.approx(wall, rel=0.02)
    assert area[tags == LABELS["bore_bottom"]].sum() == pytest.approx(bottom, rel=0.02)


@pytest.mark.parametrize("depth", [0.0, 0.001, 0.004, 0.012])
def test_removed_volume_axisymmetric_section(tmp_path, depth):
    """(r, z) section: the removed volume 2 pi int r dA equals V(d) to round-off (straight profile edges)."""
    b = D.drilled_section(tmp_path / "s.msh", depth=depth, diameter=DIA, point_angle=ANGLE, radius=0.012,
                          height=0.02, h=0.002, h_bore=0.0005)
    m = meshio.read(b.path)
    tri, p = m.cells_dict["triangle"], m.points[:, :2]
    vol = (2 * math.pi * p[tri].mean(axis=1)[:, 0] * cell_volumes(p, tri)).sum()
    assert math.pi * 0.012 ** 2 * 0.02 - vol == pytest.approx(D.bore_volume(depth, R, ANGLE), rel=1e-9, abs=1e-15)
    labels = _facet_labels(m, "line")
    assert {LABELS[n] for n in ("top", "bottom", "outer", "axis")} <= labels
    assert (LABELS["bore_bottom"] in labels) == (depth > 0)


# ---- the process loop (real gmsh + FreeFEM on tiny meshes)

from wendel.results import vtu as output  # noqa: E402
from wendel.loop import run  # noqa: E402

DRILL_SCENE = """
description = "test: drilling a block"
[geometry]
builder = "drilled-block"
x = [-0.008, 0.008]      # m
y = [-0.008, 0.008]      # m
height = 0.012           # m
h = 0.005                # m
""" + IRON + """[boundary.bottom]
ux = 0.0                 # m
uy = 0.0                 # m
uz = 0.0                 # m
[thermal]
""" + IRON_THERMAL + """coupling = "staggered"
[thermal.boundary.top]
h = 10.0                 # W/m^2/K
T_inf = 293.15           # K
""" + drill_table(0.0015)


def _drill(tmp_path, extra, name="d"):
    return drill(tmp_path, DRILL_SCENE, extra, name)


def test_drill_that_does_not_advance_is_a_heated_disc(tmp_path):
    """A drill dwelling at a fixed depth (steps that remove nothing keep the body and its mesh) gives the
    temperature of the same flux on the bore bottom of the same mesh in one plain run; energy to 1e-6."""
    dwell = 0.5
    root, dr = _drill(tmp_path, f"depth = 0.003\nstart_depth = 0.003\ndwell = {dwell}\ndwell_steps = 2\n"
                                f"wall_fraction = 0.0\nthrust = 0.0")
    assert dr["energy"]["balance_error"] < 1e-6
    assert dr["energy"]["chips_heat"] == 0.0
    mesh = meshio.read(root / "meshes" / "step-001.msh")
    tri, tags = mesh.cells_dict["triangle"], mesh.cell_data_dict["gmsh:physical"]["triangle"]
    p = mesh.points
    area = 0.5 * np.linalg.norm(np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]), axis=1)
    q = 0.3 * 2 * math.pi * 2000.0 / 60 * 1.0 / area[tags == LABELS["bore_bottom"]].sum()
    ref = DRILL_SCENE.split("[drilling]")[0].replace('builder = "drilled-block"',
                                                     'builder = "drilled-block"\ndepth = 0.003\ndiameter = 0.004\n'
                                                     'h_bore = 0.0015')
    ref = ref.replace('coupling = "staggered"', f'coupling = "staggered"\nduration = {dwell}    # s')
    ref += f"[thermal.boundary.bore_bottom]\nflux = {float(q)!r}    # W/m^2\n[loading]\nsteps = 2\n[output]\npng = false\n"
    (tmp_path / "ref.toml").write_text(ref)
    disc = run(tmp_path / "ref.toml", out=tmp_path / "ref", progress=lambda *_: None)
    t_drill = output.read_array(root / "fem" / "inc-0002" / "T.node.txt")
    t_disc = output.read_array(disc / "fem" / "inc-0002" / "T.node.txt")
    assert t_drill.max() > 300.0
    assert np.abs(t_drill - t_disc).max() <= 1e-8 * (t_disc.max() - 293.15)


def test_energy_identity_with_removal(tmp_path):
    """Heat in = heat in the body + heat left with the chips - convection, within 1 %, over a run of
    three removal steps (remesh + conservative transfer each) and a cooling to ambient; the removed
    volume of each step is the analytic one within the chord error; no stress is left after cooling."""
    root, dr = _drill(tmp_path, "depth = 0.006\nsteps = 3\ncooling = 1e6\ncooling_steps = 1\nbore_h = 50.0\n"
                                "thrust = 100.0")
    e = dr["energy"]
    assert e["chips_heat"] > 0.02 * e["heat_in"]
    assert e["convection"] < 0
    assert e["balance_error"] < 0.01
    for k in (2, 3):
        rep = json.loads((root / "remesh" / f"remesh-{k:03d}.json").read_text())
        removed = rep["measure_old"] - rep["measure_new"]
        exact = D.bore_volume(rep["depth_new"], 0.002, ANGLE) - D.bore_volume(rep["depth_old"], 0.002, ANGLE)
        assert abs(removed - exact) <= exact * (0.0015 / 0.002) ** 2 / 4      # chord error of h_bore on R
    assert len(list((root / "vtu").glob("inc-*.vtu"))) == 4
    # cooled back to ambient, a thermo-elastic body carries no stress: the transfers left none behind
    profiles = json.loads((root / "drilling.json").read_text())["profiles"]
    hot, cold = profiles[-2], profiles[-1]
    assert cold["kind"] == "cool" and hot["kind"] == "drill"
    scale = np.nanmax(np.abs(hot["hoop_stress"]))
    assert scale > 1e6
    assert np.nanmax(np.abs(cold["hoop_stress"] + cold["axial_stress"])) < 1e-3 * scale
    assert np.nanmax(np.abs(cold["diameter_error"])) < 1e-3 * np.nanmax(np.abs(hot["diameter_error"]))
    assert (root / "tables" / "drilling-steps.csv").is_file()


@pytest.mark.parametrize("change, message", [
    (('builder = "drilled-block"\nx = [-0.008, 0.008]      # m\ny = [-0.008, 0.008]      # m\nheight = 0.012           # m',
      'builder = "box"'), "geometry.builder"),
    (('force = "given"', 'force = "kienzle"'), "kc11"),
    (('height = 0.012           # m', 'height = 0.012\ndiameter = 0.004'), "geometry.diameter"),
])
def test_bad_drilling_scene_names_the_key(change, message):
    from wendel.scene import SceneError, parse
    import tomllib

    text = DRILL_SCENE.format(extra="depth = 0.004").replace(*change)
    assert text != DRILL_SCENE.format(extra="depth = 0.004")
    with pytest.raises(SceneError) as err:
        parse(tomllib.loads(text), "x.toml")
    assert "x.toml" in str(err.value) and message in str(err.value)


def test_plastic_drilling_leaves_residual_stress(tmp_path):
    """With a low yield stress the thermal stresses of drilling yield the wall: the plastic strain goes over
    at every removal (its integral kept within 10 %), and stress remains after cooling to ambient."""
    text = "depth = 0.006\nsteps = 3\ncooling = 1e6\ncooling_steps = 1\nthrust = 100.0\n[plasticity]\n" \
           "law = \"linear\"\nsigma0 = 15e6            # Pa\nH = 1e9                  # Pa"
    root, dr = _drill(tmp_path, text)
    assert dr["energy"]["balance_error"] < 0.01
    for k in (2, 3):
        rep = json.loads((root / "remesh" / f"remesh-{k:03d}.json").read_text())
        assert rep["integral_p_before"] > 0
        assert rep["integral_p_after"] == pytest.approx(rep["integral_p_before"], rel=0.1)
    profiles = json.loads((root / "drilling.json").read_text())["profiles"]
    hot, cold = profiles[-2], profiles[-1]
    assert np.nanmax(np.abs(cold["hoop_stress"])) > 0.05 * np.nanmax(np.abs(hot["hoop_stress"]))
