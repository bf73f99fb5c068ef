"""3D interior penalty DG (edp/lib/dg3d.idp: the face terms as matrices, since FreeFEM 4.9 has no jump in 3D
linear forms): a uniform strain is reproduced exactly, the cantilever agrees with Timoshenko's beam where CG P1
on the same mesh is far off, J2 plasticity matches CG on a uniform state and converges quadratically in bending,
and what 3D DG does not do is refused when the scene is read."""

from __future__ import annotations

import json

import numpy as np
import pytest

from wendel.loop import run
from wendel.results.vtu import read_array, read_vertices
from wendel.scene import SceneError, load

from conftest import WORKFLOWS, edit

PATCH = """description = "uniform strain of a box, P1 DG in 3D"
[geometry]
builder = "box"
x = [0.0, 2.0]           # m
y = [0.0, 1.0]           # m
z = [0.0, 1.0]           # m
h = 0.5                  # m
[material]
E = 1e3                  # Pa
nu = 0.3                 # 1
[boundary.left]
ux = 0.0                 # m
[boundary.right]
ux = 2e-3                # m
[boundary.front]
uy = 0.0                 # m
[boundary.bottom]
uz = 0.0                 # m
[numerics]
solver = "direct"
[discretization]
kind = "dg"
order = 1                # P1dc
"""


def test_a_3d_dg_scene_compiles_the_3d_dg_module(tmp_path):
    from test_entry import MODULES, compiled

    found, switches, record = compiled(tmp_path / "dg", "cantilever-dg-3d.toml")
    assert found & set(MODULES) == {"dg", "dg3d"}, found
    assert switches == ["-Ddimension=3", "-DPk=P1dc", "-DWITHDG=1"]
    assert record["dg_gamma_min"] == 8 and record["dg_face_assembly_s"] > 0


def test_dg_3d_reproduces_a_uniform_strain_with_per_component_nitsche_conditions(tmp_path, scene_file, quiet):
    # eps_xx = 1e-3 with free lateral faces: u = (1e-3 x, -nu 1e-3 y, -nu 1e-3 z); exact for P1, so the interior
    # face fluxes {sigma} n . [v] and the Nitsche terms of each constrained component must be consistent
    root = run(scene_file(PATCH, "patch.toml"), out=tmp_path / "run", png=False, progress=quiet)
    rec = json.loads((root / "fem" / "inc-0001" / "record.json").read_text())
    assert rec["dg_gamma_min"] == 8
    xyz = read_vertices(root / "fem" / "vertices.txt")
    u = read_array(root / "fem" / "inc-0001" / "u.node.txt").reshape(-1, 3)
    exact = np.column_stack([1e-3 * xyz[:, 0], -0.3e-3 * xyz[:, 1], -0.3e-3 * xyz[:, 2]])
    assert np.abs(u - exact).max() < 1e-9, np.abs(u - exact).max()
    # strain energy of the uniform stress E eps^2 / 2 over the 2 m^3 box
    assert rec["strain_energy"] == pytest.approx(0.5 * 1e3 * 1e-6 * 2.0, rel=1e-8)


def test_dg_3d_cantilever_p2_agrees_with_timoshenko_where_cg_p1_is_far_off(tmp_path):
    # h = 1 m (measured): DG P2 0.019941 m (-1.05 %), DG P1 0.012404, CG P1 0.012029 against 0.020153
    from wendel.bench.dg import _run
    from wendel.bench.dg3d import CANTILEVER, timoshenko

    ref = timoshenko(0.3)
    assert ref == pytest.approx(0.020153, abs=1e-6)
    got = {m: _run(CANTILEVER, m, 1.0, tmp_path / m) for m in ("cg1", "dg2")}
    assert abs(-got["dg2"]["record"]["probe_uz"] / ref - 1) < 0.02
    assert -got["cg1"]["record"]["probe_uz"] / ref < 0.7
    assert got["dg2"]["dofs"] % 30 == 0                 # 10 DoFs x 3 components per tetrahedron, none shared


PLASTIC = """
[plasticity]
law = "linear"
sigma0 = 250e6           # Pa
H = 50e9                 # Pa
"""


def test_dg_3d_plasticity_matches_cg_on_a_uniform_state_and_converges_like_it_in_bending(tmp_path, scene_file, quiet):
    import csv

    # uniaxial tension of a cube past yield (workflows/uniaxial-linear.toml, homogeneous): the same state as CG
    uni = edit((WORKFLOWS / "uniaxial-linear.toml").read_text(), "newton_tol = 1e-10", "newton_tol = 1e-10\nsolver = \"direct\"")
    roots = {k: run(scene_file(uni + extra, f"uni-{k}.toml"), smoke=True, out=tmp_path / f"uni-{k}", progress=quiet)
             for k, extra in (("cg", ""), ("dg", "\n[discretization]\nkind = \"dg\"\norder = 1\n"))}
    rows = {k: list(csv.DictReader((r / "history.csv").open())) for k, r in roots.items()}
    assert [r["newton_iterations"] for r in rows["dg"]] == [r["newton_iterations"] for r in rows["cg"]]
    for a, b in zip(rows["cg"], rows["dg"]):
        for key in ("strain_energy", "max_plastic_strain", "max_von_mises"):
            assert float(b[key]) == pytest.approx(float(a[key]), rel=1e-10), key
    last = lambda k: read_array(roots[k] / "fem" / "inc-0007" / "u.node.txt")
    assert np.abs(last("dg") - last("cg")).max() < 1e-12
    # the cantilever loaded past its limit load (8 MN, sigma0 = 250 MPa, H = 50 GPa), h = 1 m: measured CG and DG
    # both 22 plastic points and 5 Newton iterations in the last increment, DG 5.4e-7 -> 1.1e-11 (quadratic with
    # the consistent face tangent); tip 0.1062 (CG) and 0.1087 m (DG)
    text = (WORKFLOWS / "cantilever-dg-3d.toml").read_text().replace("[numerics]", PLASTIC + "\n[numerics]")
    text = edit(edit(text, "traction = [0.0, 0.0, -1e6]", "traction = [0.0, 0.0, -8e6]"), "steps = 1", "steps = 4")
    root = run(scene_file(text, "cant.toml"), smoke=True, out=tmp_path / "cant", png=False, progress=quiet)
    rec = json.loads((root / "fem" / "inc-0004" / "record.json").read_text())
    newton = list(csv.DictReader((root / "fem" / "inc-0004" / "newton.csv").open()))
    assert rec["plastic_points"] > 10 and len(newton) <= 7
    rel = [float(r["relative_residual"]) for r in newton]
    assert rel[-2] < 1e-5 and rel[-1] < 1e-9
    assert 0.10 < -rec["probe_uz"] < 0.115


@pytest.mark.parametrize("changes, message", [
    ([("gamma_lambda = 25.0 ", "separation_stress = 1e6\ngamma_lambda = 25.0 ")], "3D has no separation_stress"),
    ([("gamma_lambda = 25.0 ", "region = [[0.0, 0.0], [1.0, 1.0]]\ngamma_lambda = 25.0 ")], "and no region"),
])
def test_what_3d_dg_does_not_do_is_refused_when_the_scene_is_read(scene_file, changes, message):
    text = (WORKFLOWS / "cantilever-dg-3d.toml").read_text()
    for change in changes:
        text = edit(text, *change)
    path = scene_file(text)
    with pytest.raises(SceneError) as err:
        load(path)
    assert message in str(err.value) and str(path) in str(err.value)
