"""Inexact Newton (``numerics.forcing = "ew"``, lib/solver.idp's solverForcing): the Newton steps' linear solves
stop at an Eisenstat-Walker forcing term instead of ``solver_tol``, and the Newton tolerance is unchanged, so the
step-42 ball (contact + plasticity) ends at the direct solver's result to 1e-7 with its KKT conditions met, with
far fewer Krylov iterations; a direct solver with ``forcing = "ew"`` is refused naming the key."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from conftest import WORKFLOWS, smoke_ball


def solve(solver: str, forcing: str, out) -> dict:
    root = smoke_ball(out, solver=solver, forcing=forcing)
    return json.loads((root / "summary.json").read_text()) | {"root": root}


@pytest.fixture(scope="module")
def ball(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("forcing")
    runs = {(s, f): solve(s, f, tmp / f"{s}-{f}") for s, f in
            (("direct", "fixed"), ("petsc", "fixed"), ("petsc", "ew"), ("cg", "fixed"), ("cg", "ew"))}
    runs["again"] = solve("petsc", "ew", tmp / "petsc-ew-again")
    return runs


@pytest.mark.parametrize("solver", ["petsc", "cg"])
def test_inexact_newton_ends_at_the_same_result(ball, solver):
    d, e, f = ball[("direct", "fixed")], ball[(solver, "ew")], ball[(solver, "fixed")]
    assert d["completed"] and e["completed"] and f["completed"]
    ld, le, lf = d["last_increment"], e["last_increment"], f["last_increment"]
    for key in ("contact_force", "max_displacement", "max_von_mises", "plastic_volume"):
        assert le[key] == pytest.approx(ld[key], rel=1e-7), key
    assert le["contact_active_nodes"] == ld["contact_active_nodes"] > 0
    assert max(le[k] for k in ("kkt_max_penetration", "kkt_min_pressure", "kkt_max_complementarity")) < 1e-8
    # the Newton tolerance is the same, so the step count stays close; the Krylov work falls
    assert e["newton_iterations"] <= f["newton_iterations"] + 2
    assert le["linear_iterations"] < 0.6 * lf["linear_iterations"]


def test_keeping_the_preconditioner_is_decided_alike_in_every_run(ball):
    """The plugin keeps or sets up its preconditioner on iteration counts, not on measured times, so a run
    takes the same Krylov path again (a timed rule moved the Newton count by one between runs of one scene)."""
    def path(run):
        lines = (run["root"] / "newton.csv").read_text().splitlines()
        col = lines[0].split(",").index("linear_iterations")
        return [line.split(",")[col] for line in lines[1:] if not line.startswith("increment")]
    first, again = ball[("petsc", "ew")], ball["again"]
    assert path(first) == path(again) and len(path(first)) > 3
    assert first["newton_iterations"] == again["newton_iterations"]


def test_forcing_needs_an_iterative_solver(tmp_path):
    scene = tmp_path / "bad.toml"
    text = (WORKFLOWS / "ball-indent.toml").read_text()
    text = text.replace('solver = "petsc"', 'solver = "direct"\nforcing = "ew"', 1)
    scene.write_text(text)
    r = subprocess.run([sys.executable, "-m", "wendel.cli", "check", str(scene)], capture_output=True, text=True)
    assert r.returncode == 2
    assert "numerics" in r.stderr and "forcing" in r.stderr and "bad.toml" in r.stderr
    assert "Traceback" not in r.stderr
