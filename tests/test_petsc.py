"""The PETSc solver path (edp/plugins/wendel_petsc.cpp through lib/petsc.idp): the same Newton iterates as the
direct solver on step-42's ball (contact + plasticity) for every preconditioner preset and on 2 ranks, Dirichlet
values entering the first Newton step, and a bad options string refused with its key named."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from wendel.loop import run_scene
from wendel.scene import load

from conftest import WORKFLOWS


def solve(name: str, solver: str, out, pc: str = "ml", options: str = "", ranks: int = 1) -> dict:
    path = WORKFLOWS / f"{name}.toml"
    scene = load(path, smoke=True)
    scene.numerics.solver = solver
    scene.numerics.ranks = ranks
    scene.numerics.petsc.pc = pc
    scene.numerics.petsc.options = options
    scene.output.png = False
    root = run_scene(scene, path, out, smoke=True, progress=lambda *_: None)
    return json.loads((root / "summary.json").read_text())


@pytest.fixture(scope="module")
def ball_direct(tmp_path_factory):
    return solve("ball-indent", "direct", tmp_path_factory.mktemp("direct"))


@pytest.mark.parametrize("pc", ["gamg", "hypre", "ml"])
def test_petsc_agrees_with_direct_on_contact_plasticity(tmp_path, ball_direct, pc):
    p = solve("ball-indent", "petsc", tmp_path / pc, pc=pc)
    d = ball_direct
    assert d["completed"] and p["completed"]
    ld, lp = d["last_increment"], p["last_increment"]
    assert lp["solver"] == "petsc"
    assert lp["contact_force"] == pytest.approx(ld["contact_force"], rel=1e-7)
    assert lp["max_displacement"] == pytest.approx(ld["max_displacement"], rel=1e-7)
    assert lp["max_von_mises"] == pytest.approx(ld["max_von_mises"], rel=1e-7)
    assert p["newton_iterations"] == d["newton_iterations"]
    assert lp["contact_active_nodes"] == ld["contact_active_nodes"] > 0
    # AMG: a few Krylov iterations per Newton step, not one (direct) and not hundreds (Jacobi)
    assert 2 * lp["newton_iterations"] < lp["linear_iterations"] < 60 * lp["newton_iterations"]


def test_petsc_two_ranks(tmp_path, ball_direct):
    """Two ranks: each builds its block of rows of the distributed matrix; the same iterates."""
    p = solve("ball-indent", "petsc", tmp_path / "np2", ranks=2)
    ld, lp = ball_direct["last_increment"], p["last_increment"]
    assert lp["ranks"] == 2
    assert lp["contact_force"] == pytest.approx(ld["contact_force"], rel=1e-7)
    assert lp["max_displacement"] == pytest.approx(ld["max_displacement"], rel=1e-7)
    assert p["newton_iterations"] == ball_direct["newton_iterations"]


def test_ml_keeps_its_interpolation_on_two_ranks_only(tmp_path, ball_direct):
    """ML's preset on 2+ ranks keeps the aggregation and interpolation of its first setup at a new setup (fewer
    Krylov iterations there, README "2 ranks"); one rank keeps the plain preset, whose iterates it would move;
    the user's options still override it. Every variant gives the direct solver's iterates."""
    runs = {"np1": solve("ball-indent", "petsc", tmp_path / "np1"),
            "np2": solve("ball-indent", "petsc", tmp_path / "np2", ranks=2),
            "np2-off": solve("ball-indent", "petsc", tmp_path / "np2-off", ranks=2,
                             options="-pc_ml_reuse_interpolation false")}
    ld = ball_direct["last_increment"]
    for name, s in runs.items():
        lp = s["last_increment"]
        assert lp["contact_force"] == pytest.approx(ld["contact_force"], rel=1e-7), name
        assert s["newton_iterations"] == ball_direct["newton_iterations"], name
        assert lp["petsc_setups"] >= 1, name
    opts = {name: s["last_increment"]["petsc_options"].split() for name, s in runs.items()}
    assert "-pc_ml_reuse_interpolation" not in opts["np1"]
    i = opts["np2"].index("-pc_ml_reuse_interpolation")
    assert opts["np2"][i + 1] == "true"
    assert opts["np2-off"][-2:] == ["-pc_ml_reuse_interpolation", "false"]     # after the preset: PETSc takes the last


def test_petsc_prescribed_displacement(tmp_path):
    """Non-zero Dirichlet values enter the first Newton step: lifted, not put on tgv rows."""
    d = solve("uniaxial-linear", "direct", tmp_path / "direct")
    p = solve("uniaxial-linear", "petsc", tmp_path / "petsc", options="-ksp_rtol 1e-11")
    ld, lp = d["last_increment"], p["last_increment"]
    assert lp["max_von_mises"] == pytest.approx(ld["max_von_mises"], rel=1e-7)
    assert lp["max_displacement"] == pytest.approx(ld["max_displacement"], rel=1e-7)
    assert p["newton_iterations"] == d["newton_iterations"]


@pytest.mark.parametrize("options, why", [
    ("-ksp_type cg;reboot", "only letters"),
    ("-ksp_rtol", "pairs"),
    ("-ksp_view_mat binary", "read or write files"),
    ("-options_file x", "read or write files"),
    ("-start_in_debugger gdb", "start programs"),
    ("ksp_rtol 1e-8", "not an option name"),
])
def test_bad_petsc_options_refused(tmp_path, options, why):
    scene = tmp_path / "bad.toml"
    text = (WORKFLOWS / "ball-indent.toml").read_text()
    text = text.replace('solver = "cg"', 'solver = "petsc"', 1) + f'\n[numerics.petsc]\noptions = "{options}"\n'
    scene.write_text(text)
    r = subprocess.run([sys.executable, "-m", "wendel.cli", "check", str(scene)], capture_output=True, text=True)
    assert r.returncode == 2
    assert "numerics.petsc.options" in r.stderr and why in r.stderr and "bad.toml" in r.stderr
    assert "Traceback" not in r.stderr


def test_mumps_direct_agrees_with_umfpack_on_contact_plasticity(tmp_path, ball_direct):
    """numerics.direct = "mumps": the direct solve by MUMPS's LU through the plugin, the same iterates as UMFPACK64."""
    path = WORKFLOWS / "ball-indent.toml"
    scene = load(path, smoke=True)
    scene.numerics.solver, scene.numerics.direct, scene.output.png = "direct", "mumps", False
    root = run_scene(scene, path, tmp_path / "mumps", smoke=True, progress=lambda *_: None)
    m = json.loads((root / "summary.json").read_text())
    assert "-DWITHPETSCLU=1" in (root / "freefem.log").read_text()
    ld, lm = ball_direct["last_increment"], m["last_increment"]
    for key in ("contact_force", "max_displacement", "max_von_mises"):
        assert lm[key] == pytest.approx(ld[key], rel=1e-9), key
    assert m["newton_iterations"] == ball_direct["newton_iterations"]
    assert lm["contact_active_nodes"] == ld["contact_active_nodes"] > 0


def test_mumps_direct_solves_the_frictional_fbar_cut(tmp_path):
    """The FE cut's Newton matrix (friction: not symmetric; F-bar: 36 entries a row) by MUMPS: the steel scene's
    smoke cut with F-bar gives UMFPACK64's forces."""
    from wendel.cutting.fe_run import run_cut
    steel = WORKFLOWS / "cutting-aisi1045.toml"
    forces = {}
    for lib in ("umfpack", "mumps"):
        cut = load(steel, smoke=True)
        cut.cutting.volumetric = "fbar"
        cut.numerics.direct = lib
        root = run_cut(cut, steel, tmp_path / lib, smoke=True, progress=lambda *_: None, frames=False)
        forces[lib] = [float(r.split(",")[3]) for r in (root / "cutting.csv").read_text().splitlines()[1:]]
        assert ("-DWITHPETSCLU=1" in (root / "freefem.log").read_text()) == (lib == "mumps")
    assert len(forces["mumps"]) == len(forces["umfpack"]) >= 4
    assert forces["mumps"] == pytest.approx(forces["umfpack"], rel=1e-8)


def test_mumps_is_refused_beside_an_iterative_solver(tmp_path):
    scene = tmp_path / "bad.toml"
    text = (WORKFLOWS / "ball-indent.toml").read_text()
    assert 'solver = "petsc"' in text
    scene.write_text(text.replace('solver = "petsc"', 'solver = "petsc"\ndirect = "mumps"', 1))
    r = subprocess.run([sys.executable, "-m", "wendel.cli", "check", str(scene)], capture_output=True, text=True)
    assert r.returncode == 2
    assert "numerics" in r.stderr and "solver = \"direct\"" in r.stderr and "bad.toml" in r.stderr
    assert "Traceback" not in r.stderr
