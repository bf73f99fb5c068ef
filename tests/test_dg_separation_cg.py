"""A separating DG run that goes on with CG on its remeshed bodies (``[discretization] after_separation = "cg"``,
driver/wendel/loop/separated.py): the notched plate (workflows/dg-separation-cg.toml at smoke size, h = 0.07 m)
separates in two, is remeshed with the cut as boundary ``opened`` and continues with CG in the same run; the
force drops to nothing and stays there; a run killed after the switch resumes to the same result."""

from __future__ import annotations

import csv
import json

import meshio
import numpy as np
import pytest

from wendel.loop import run
from wendel.remesh.bodies import body_index
from wendel.results.vtu import read_array

from conftest import WORKFLOWS, kill_after_increment


def _history(root):
    return list(csv.DictReader((root / "history.csv").open()))


def test_the_notched_plate_separates_is_remeshed_and_goes_on_with_cg_and_resumes_after_a_kill(tmp_path, quiet):
    scene = WORKFLOWS / "dg-separation-cg.toml"
    root = run(scene, smoke=True, out=tmp_path / "ref", png=False, progress=quiet)
    rows = _history(root)
    lf = [float(r["load_factor"]) for r in rows]
    force = np.array([float(r["dg_reaction_y"]) for r in rows])
    seg = json.loads((root / "checkpoint.json").read_text())["segments"]
    # measured: DG to load factor 0.5 (35 faces open at 0.4, the plate in two pieces at 0.5), then CG from
    # increment 6 (the re-equilibration at 0.5) to 1
    assert [s.get("discretization", "dg") for s in seg] == ["dg", "cg"]
    first_cg = seg[1]["first"]
    assert lf[first_cg - 1] == lf[first_cg - 2] and lf[-1] == 1.0
    assert rows[first_cg - 1]["reequilibration"] == "1"
    assert any("cut the body into 2 pieces" in line for line in quiet.__self__)
    peak = force.max()
    assert peak > 1e8                                                  # 1.27e8 N/m at 0.3 (test_dg.py)
    # after the separation the force drops and stays near zero through the CG increments (the pieces are free)
    assert np.all(np.abs(force[first_cg - 2:]) < 1e-6 * peak), force
    # the new mesh: two bodies, the cut is its boundary 'opened' (both sides), as long as the opened faces
    sep = json.loads((root / "separated.json").read_text())
    assert sep["bodies"] == 2 and sep["increment"] == first_cg - 1
    m = meshio.read(root / seg[1]["mesh"], file_format="gmsh")
    assert m.field_data["opened"].tolist() == [31, 1]
    tris = m.cells_dict["triangle"]
    assert body_index(tris).max() + 1 == 2
    lines = np.concatenate([c.data[m.cell_data["gmsh:physical"][i] == 31] for i, c in enumerate(m.cells) if c.type == "line"])
    p = m.points[:, :2]
    assert np.linalg.norm(p[lines[:, 1]] - p[lines[:, 0]], axis=1).sum() / 2 == pytest.approx(sep["opened_length"], rel=1e-3)
    # the upper piece moves with the grip, the lower one stays: across the cut the displacement jumps by the grip's
    u = read_array(root / "fem" / f"inc-{len(rows):04d}" / "u_total.node.txt").reshape(-1, 2)
    body = np.full(len(p), -1)
    for k in range(3):
        body[tris[:, k]] = body_index(tris)
    twins = {}
    for v in np.unique(lines):
        twins.setdefault(tuple(np.round(p[v], 12)), []).append(v)
    across = [vs for vs in twins.values() if len(vs) == 2 and body[vs[0]] != body[vs[1]]]
    assert len(across) >= 10
    jump = np.array([abs(u[a, 1] - u[b, 1]) for a, b in across])
    np.testing.assert_allclose(jump, 4e-3, rtol=1e-9)

    # killed (SIGKILL) in the CG part of the run, resumed: the same rows and the same last field
    killed = tmp_path / "killed"
    kill_after_increment(scene, killed, first_cg + 1)
    again = _history(killed)
    assert [(a["increment"], a["load_factor"], a["newton_iterations"]) for a in again] == \
        [(a["increment"], a["load_factor"], a["newton_iterations"]) for a in rows]
    for a, b in zip(rows, again):
        assert float(b["dg_reaction_y"]) == pytest.approx(float(a["dg_reaction_y"]), rel=1e-8, abs=1e-6 * peak)
    np.testing.assert_allclose(read_array(killed / "fem" / f"inc-{len(rows):04d}" / "u_total.node.txt").reshape(-1, 2),
                               u, rtol=1e-9, atol=1e-15)
