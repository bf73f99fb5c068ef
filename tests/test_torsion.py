"""Elastic-plastic torsion of a bar (problem ``torsion``: Prandtl stress function as an obstacle problem,
PDAS of edp/obstacle.edp): circular bar against its closed forms, convergence, a square bar's elastic and
fully plastic torques (the distance function of a general section), bad input."""

from __future__ import annotations

import csv
import json
import math

import pytest

from wendel.scene.blocks.torsion import circular_torque
from wendel.loop import run
from wendel.scene import SceneError

from conftest import WORKFLOWS

MU, TAU, R = 80e9, 200e6, 0.01
SCENE = (WORKFLOWS / "torsion.toml").read_text()


def records(root):
    return [json.loads(p.read_text()) for p in sorted((root / "fem").glob("inc-*/record.json"))]


def test_closed_form_limits():
    theta_e = TAU / (MU * R)
    assert circular_torque(theta_e, MU, TAU, R) == pytest.approx(math.pi / 2 * TAU * R ** 3, rel=1e-12)
    assert circular_torque(1e6 * theta_e, MU, TAU, R) == pytest.approx(2 * math.pi / 3 * TAU * R ** 3, rel=1e-12)
    assert circular_torque(0.5 * theta_e, MU, TAU, R) == pytest.approx(math.pi / 4 * TAU * R ** 3, rel=1e-12)


def test_circular_bar_matches_closed_form(tmp_path, quiet):
    root = run(WORKFLOWS / "torsion.toml", out=tmp_path / "run", png=False, progress=quiet)   # h = R/8
    recs = records(root)
    assert len(recs) == 6
    for r in recs:
        theta = r["twist"]
        assert r["closed_form_torque"] == pytest.approx(circular_torque(theta, MU, TAU, R), rel=1e-12)
        assert abs(r["torque"] / r["closed_form_torque"] - 1) < 0.015, r      # measured 0.75-0.98 %
        if theta <= TAU / (MU * R):      # elastic: nothing yields, torque = (pi/2) mu theta R^4 (discretely linear)
            assert r["active_nodes"] == 0
        else:                            # KKT relative to max lambda: meaningful once something yields
            assert r["active_nodes"] > 0 and r["error_core_radius"] < 0.08
            assert all(r[k] < 1e-8 for k in ("kkt_max_penetration", "kkt_min_pressure", "kkt_max_complementarity"))
    # past the elastic limit the torque grows towards, and stays below, the fully plastic torque
    torques = [r["torque"] for r in recs]
    assert all(a < b for a, b in zip(torques, torques[1:]))
    assert torques[-1] < recs[-1]["fully_plastic_torque"]
    import meshio

    mesh = meshio.read(root / "vtu" / "inc-0006.vtu")
    assert {"phi", "active", "lambda"} <= set(mesh.point_data) and "tau" in mesh.cell_data


def test_study_converges(tmp_path):
    from wendel.results.study import study

    root = study(WORKFLOWS / "torsion.toml", levels=3, smoke=True, out=tmp_path / "study", progress=lambda *_: None)
    with open(root / "study.csv") as f:
        rows = list(csv.DictReader(f))
    assert float(rows[-1]["rate_torque"]) > 1.6            # measured 1.86, 1.96 (polygonal section: O(h^2))
    assert float(rows[-1]["rate_l2_relative"]) > 1.6
    assert float(rows[-1]["rate_h1_relative"]) > 0.8
    assert float(rows[-1]["error_torque"]) < 0.005
    assert (root / "error_vs_runtime.png").is_file()


SQUARE = """description = "torsion of a square bar"
problem = "torsion"
[geometry]
builder = "rectangle"
x = [-0.01, 0.01]
y = [-0.01, 0.01]
h = 0.001
structured = true
[torsion]
mu = 80e9
tau_y = 200e6
theta = {theta}
[output]
png = false
"""


@pytest.mark.parametrize("factor, expected", [
    (0.5, lambda a, th: 0.1406 * MU * th * a ** 4),      # elastic (Saint-Venant; Timoshenko k = 0.1406)
    (200.0, lambda a, th: TAU * a ** 3 / 3),             # fully plastic: sand-heap roof of slope tau_y
])
def test_square_bar(scene_file, tmp_path, quiet, factor, expected):
    a = 0.02
    theta = factor * TAU / (0.675 * MU * a)              # elastic limit: max shear 0.675 mu theta a
    root = run(scene_file(SQUARE.format(theta=repr(theta))), out=tmp_path / "run", png=False, progress=quiet)
    r = records(root)[-1]
    assert r["torque"] == pytest.approx(expected(a, theta), rel=0.02)
    assert (r["active_nodes"] == 0) == (factor < 1)


def test_circular_reference_needs_a_disk(scene_file, tmp_path, quiet):
    path = scene_file(SQUARE.format(theta="1.0").replace("theta = 1.0", "theta = 1.0\nreference = \"circular\""))
    with pytest.raises((SceneError, ValueError), match="disk"):
        run(path, out=tmp_path / "run", png=False, progress=quiet)
