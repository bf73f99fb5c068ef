"""The extrapolated first guess across launches (``wendel.loop.predictor``, ``edp/lib/predictor.idp``'s
``-predictor_du``): the first increment that moves the tool after a remesh starts from the old mesh's last
motion, interpolated onto the new mesh, instead of from the re-equilibrated state with the tool a whole step
deep in the material (measured on the 300 um graded cut: a first relative residual of 30-68 there against
0.3-1 in the increments inside a launch; here 38-42 before, 3.4-6.1 now)."""

import csv
import json

import numpy as np
import pytest

from wendel.cutting.fe_run import run_cut
from wendel.results import vtu
from wendel.scene import load

from conftest import WORKFLOWS

STEEL = WORKFLOWS / "cutting-aisi1045.toml"


def first_residuals(root):
    return {int(r["increment"]): float(r["relative_residual"])
            for r in csv.DictReader((root / "newton.csv").open()) if r["iteration"] == "0"}


def test_the_first_move_after_a_remesh_starts_from_the_last_motion(tmp_path):
    scene = load(STEEL, smoke=True)
    scene.geometry.model_extra["length"] = 1.2e-3      # m: a short block (the cut is 30 um)
    scene.cutting.cut_length = 0.03e-3                 # m: 6 increments of 5 um
    scene.loading.steps = 6
    scene.cutting.remesh_every = 2
    root = run_cut(scene, STEEL, tmp_path / "cut", smoke=False, progress=lambda *_: None, frames=False)
    hist = list(csv.DictReader((root / "history.csv").open()))
    reeq = [int(r["increment"]) for r in hist if r["reequilibration"] == "1"]
    assert len(reeq) >= 2
    first = first_residuals(root)
    after = [first[k + 1] for k in reeq if k + 1 in first]
    inside = [r for k, r in first.items() if k > 1 and k not in reeq and k - 1 not in reeq]
    # measured: 6.1 and 3.4 after the two remeshes (41.8 and 37.9 from u_n before), 9.3, 7.8 and 0.45 inside
    assert after and max(after) < max(inside), (after, inside)
    launches = [line for line in (root / "freefem.log").read_text().splitlines() if line.startswith("$ ")]
    relaunch = [line for line in launches if "-relax_steps" in line]      # the re-equilibrations
    assert len(relaunch) >= 2 and all("-predictor_du" in line for line in relaunch)
    # the motion on the new mesh: the transferred displacement increment of the last increment before the remesh
    seg = json.loads((root / "checkpoint.json").read_text())["segments"][1]
    du = vtu.read_array(root / seg["state"] / "predictor_du.txt").reshape(-1, 2)
    points, _ = vtu.read_mesh(root / seg["mesh"], 2)
    assert len(du) == len(points)
    assert np.abs(du).max() == pytest.approx(5e-3, rel=0.5)     # mm: about the tool's 5 um step near the edge
