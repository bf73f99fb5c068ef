"""The linear solvers of edp/lib/solver.idp give the same Newton iterates: CG (Jacobi-preconditioned, on the
free DoFs with Dirichlet and active contact rows as a mask, lifted prescribed values) against the sparse
direct solver, on a scene with contact and plasticity (step-42's ball) and on one with a prescribed
displacement (the Dirichlet values enter the first Newton step of each increment)."""

from __future__ import annotations

import json

import pytest

from wendel.loop import run_scene
from wendel.scene import load

from conftest import WORKFLOWS


def solve(name: str, solver: str, out) -> dict:
    path = WORKFLOWS / f"{name}.toml"
    scene = load(path, smoke=True)
    scene.numerics.solver = solver
    scene.output.png = False
    root = run_scene(scene, path, out, smoke=True, progress=lambda *_: None)
    return json.loads((root / "summary.json").read_text())


@pytest.mark.parametrize("name, quantity", [("ball-indent", "contact_force"), ("uniaxial-linear", "max_von_mises")])
def test_cg_and_direct_agree(tmp_path, name, quantity):
    d = solve(name, "direct", tmp_path / "direct")
    c = solve(name, "cg", tmp_path / "cg")
    assert d["completed"] and c["completed"]
    ld, lc = d["last_increment"], c["last_increment"]
    assert lc[quantity] == pytest.approx(ld[quantity], rel=1e-7)
    assert lc["max_displacement"] == pytest.approx(ld["max_displacement"], rel=1e-7)
    assert c["newton_iterations"] == d["newton_iterations"]
    # CG reports its own iterations: more than one per Newton step
    assert lc["linear_iterations"] > 2 * lc["newton_iterations"]
    if name == "ball-indent":
        assert lc["contact_active_nodes"] == ld["contact_active_nodes"] > 0
