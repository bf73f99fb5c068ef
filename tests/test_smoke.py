"""The smoke scene end to end: 1 and 2 ranks agree, ParaView files, picture, summary, study rates."""

import csv
import json

import meshio
import numpy as np
import pytest

from wendel.results import vtu as output
from wendel.loop import run
from wendel.results.study import study

from conftest import WORKFLOWS


@pytest.fixture(scope="module")
def smoke_runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("smoke")
    one = run(WORKFLOWS / "smoke.toml", smoke=True, ranks=1, out=root / "np1", progress=lambda *_: None)
    two = run(WORKFLOWS / "smoke.toml", smoke=True, ranks=2, out=root / "np2", png=False, progress=lambda *_: None)
    return one, two


def test_one_and_two_ranks_agree(smoke_runs):
    one, two = smoke_runs
    u1 = output.read_array(one / "fem" / "inc-0001" / "u.node.txt")
    u2 = output.read_array(two / "fem" / "inc-0001" / "u.node.txt")
    assert np.linalg.norm(u1 - u2) <= 1e-8 * np.linalg.norm(u1)
    s1 = json.loads((one / "summary.json").read_text())
    s2 = json.loads((two / "summary.json").read_text())
    assert (s1["ranks"], s2["ranks"]) == (1, 2)
    assert s1["solver"] == s2["solver"] == "ffddm"
    assert s2["last_increment"]["linear_iterations"] > 1


def test_vtu_and_pvd_read_back(smoke_runs):
    one, _ = smoke_runs
    entries = output.read_pvd(one / "results.pvd")
    assert [t for t, _ in entries] == [1.0]
    mesh = meshio.read(entries[0][1])
    u = mesh.point_data["u"]
    assert u.shape == (len(mesh.points), 3) and np.all(u[:, 2] == 0)
    vm = mesh.cell_data["vonMises"][0]
    assert vm.shape == (len(mesh.cells[0].data),) and vm.max() > 0
    # step-8: the x force pushes the discs at (+-0.5, 0) to the right
    near = np.linalg.norm(mesh.points[:, :2] - [0.5, 0.0], axis=1) < 0.2
    assert u[near, 0].mean() > 0


def test_picture_is_not_blank(smoke_runs):
    one, _ = smoke_runs
    import matplotlib.image

    img = matplotlib.image.imread(one / "deformed.png")
    assert img.shape[0] > 300 and img.shape[1] > 300
    rgb = img[..., :3].reshape(-1, 3)
    background = np.median(rgb, axis=0)
    assert (np.abs(rgb - background).sum(axis=1) > 0.1).mean() > 0.1   # a body, not an empty frame
    assert len(np.unique(rgb.round(2), axis=0)) > 20                    # colour map shown


def test_summary_states_phases_and_shares(smoke_runs):
    one, _ = smoke_runs
    s = json.loads((one / "summary.json").read_text())
    phases = s["wall_time_by_phase"]
    for key in ("mesh", "freefem_startup", "assembly", "linear_solve", "freefem_output", "driver_output"):
        assert phases[key] >= 0
    assert 0 < s["share_startup_and_io"] < 1
    assert s["completed"] and s["increments"] == 1 and s["dofs"] > 0
    prov = json.loads((one / "provenance.json").read_text())
    assert prov["versions"]["freefem++"].startswith("4.") and "gmsh" in prov["versions"]
    assert prov["start"] <= prov["end"] and prov["git_commit"]
    assert (one / "scene.toml").is_file() and (one / "freefem.log").is_file()


def test_manufactured_solution_converges_at_the_element_order(tmp_path):
    root = study(WORKFLOWS / "smoke-mms.toml", levels=3, smoke=True, out=tmp_path / "study", progress=lambda *_: None)
    rows = list(csv.DictReader(open(root / "study.csv")))
    assert len(rows) == 3
    assert abs(float(rows[-1]["rate_h1"]) - 1.0) < 0.2      # P1: H1 error ~ h
    assert abs(float(rows[-1]["rate_l2"]) - 2.0) < 0.2      # and L2 error ~ h^2
    assert float(rows[-1]["error_h1"]) < float(rows[0]["error_h1"])
    assert (root / "error_vs_runtime.png").stat().st_size > 10000


def test_study_against_the_finest_run(tmp_path):
    root = study(WORKFLOWS / "smoke.toml", levels=3, smoke=True, out=tmp_path / "study", progress=lambda *_: None)
    rows = list(csv.DictReader(open(root / "study.csv")))
    assert len(rows) == 2           # the finest run is the reference
    errs = [float(r["error_strain_energy"]) for r in rows]
    assert errs[1] < errs[0]


def test_np_override_puts_a_plastic_scene_on_two_ranks(tmp_path):
    """`--np 2` on a scene with the default direct solver switches it to ffddm; same answer as 1 rank."""
    from wendel.cli import main

    assert main(["run", str(WORKFLOWS / "cylinder.toml"), "--smoke", "--np", "2", "--out", str(tmp_path / "np2")]) == 0
    one = run(WORKFLOWS / "cylinder.toml", smoke=True, out=tmp_path / "np1", png=False, progress=lambda *_: None)
    s2 = json.loads((tmp_path / "np2" / "summary.json").read_text())
    assert s2["ranks"] == 2 and s2["solver"] == "ffddm"
    last = f"inc-{s2['increments']:04d}"
    u1 = output.read_array(one / "fem" / last / "u.node.txt")
    u2 = output.read_array(tmp_path / "np2" / "fem" / last / "u.node.txt")
    assert np.abs(u1 - u2).max() <= 1e-8 * np.abs(u1).max()
