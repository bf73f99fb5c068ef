"""deal.II step-42 in 3D (workflows/ball-indent.toml, workflows/stamp-indent.toml): elastoplastic contact of a
unit cube with a ball and a stamp. Small meshes only: the fingerprints are checked for their physics (force,
active set inside the obstacle's shadow, plastic zone, Newton count of step-42's order), the parallel path
for identical results on 1 and 2 ranks, and step-42's yield convention for its one-to-one mapping."""

from __future__ import annotations

import json
import math

import meshio
import numpy as np
import pytest

from wendel.results import vtu as output
from wendel.scene.blocks.plasticity import Plasticity, options, step42_to_von_mises
from wendel.loop import run
from wendel.scene import load

from conftest import WORKFLOWS

FINGERPRINTS = ("contact_force", "contact_active_nodes", "contact_max_pressure", "plastic_volume", "newton_iterations")


def summary(root) -> dict:
    return json.loads((root / "summary.json").read_text())


def test_step42_convention_is_linear_hardening_in_von_mises_form():
    """|s| = sigma0 + gamma (|s_trial| - sigma0) (step-42) equals the radial return of linear hardening with
    sigma_y0 = sqrt(3/2) sigma0 and H = 3 mu gamma / (1 - gamma) (von Mises form), for any trial stress."""
    E, nu, s0, gamma = 200000.0, 0.3, 400.0, 0.01
    mu = E / (2 * (1 + nu))
    sy0, H = step42_to_von_mises(s0, gamma, E, nu)
    for s_trial in (401.0, 800.0, 5000.0):          # Frobenius norm of the deviatoric trial stress
        q_trial = math.sqrt(1.5) * s_trial           # von Mises trial stress
        dp = (q_trial - sy0) / (3 * mu + H)          # radial return, linear hardening
        q = q_trial - 3 * mu * dp
        assert q / math.sqrt(1.5) == pytest.approx(s0 + gamma * (s_trial - s0), rel=1e-12)
    scene = load(WORKFLOWS / "ball-indent.toml")
    opts = options(scene.plasticity, scene, None)
    assert opts[opts.index("-plast_law") + 1] == "1"
    assert float(opts[opts.index("-plast_sigma0") + 1]) == pytest.approx(sy0)
    assert float(opts[opts.index("-plast_H") + 1]) == pytest.approx(H)
    with pytest.raises(ValueError, match="needs sigma0"):
        Plasticity(law="step42", gamma=0.01)


def test_ball_indent_reports_step42_fingerprints_and_fields(tmp_path):
    root = run(WORKFLOWS / "ball-indent.toml", smoke=True, out=tmp_path / "ball", progress=lambda *_: None,
               scale=0.25 / 0.4)      # smoke h = 0.4 -> 0.25 (contact zone h/8)
    s = summary(root)
    last = s["last_increment"]
    assert s["completed"]
    for key in FINGERPRINTS:
        assert key in last, key
    assert last["contact_force"] > 0 and last["contact_active_nodes"] > 0 and last["plastic_volume"] > 0
    # the pressure peaks far above the yield stress only under the ball: a few times sqrt(3/2) 400
    assert 400 < last["contact_max_pressure"] < 10000
    assert 2 <= last["newton_iterations"] <= 14      # step-42: 7 at 14,739 DoFs (within 2x)
    assert max(last[k] for k in ("kkt_max_penetration", "kkt_min_pressure", "kkt_max_complementarity")) < 1e-8
    mesh = meshio.read(root / "vtu" / "inc-0001.vtu")
    assert {"u", "contact_pressure", "contact_active"} <= set(mesh.point_data)
    assert "plastic" in mesh.cell_data
    # active nodes lie in the ball's shadow: within the circle where the ball is below z = 1
    act = mesh.points[mesh.point_data["contact_active"] > 0.5]
    r = np.hypot(act[:, 0] - 0.5, act[:, 1] - 0.5)
    assert r.max() < math.sqrt(0.6 ** 2 - 0.59 ** 2) + 0.1


def test_stamp_indent_touches_only_the_raised_pixels(tmp_path):
    root = run(WORKFLOWS / "stamp-indent.toml", smoke=True, out=tmp_path / "stamp", progress=lambda *_: None)
    s = summary(root)
    last = s["last_increment"]
    assert s["completed"] and last["contact_active_nodes"] > 0 and last["contact_force"] > 0
    assert last["newton_iterations"] <= 10           # step-42: 5 at 14,739 DoFs
    active = output.read_array(root / "fem" / "inc-0001" / "contact_active.node.txt")
    pts = output.read_vertices(root / "fem" / "vertices.txt")
    tokens = [t for line in (WORKFLOWS / "images" / "stamp-character.pgm").read_text().splitlines()
              if not line.startswith("#") for t in line.split()]
    nx, ny = int(tokens[1]), int(tokens[2])
    img = np.array(tokens[4:], dtype=float).reshape(ny, nx) / 255.0
    for x, y, _ in pts[active > 0.5]:
        # bilinear footprint of the node: some raised pixel among its neighbours (rows run downwards)
        i, j = x * (nx - 1), (1 - y) * (ny - 1)
        near = img[int(max(j - 1, 0)):int(j + 2), int(max(i - 1, 0)):int(i + 2)]
        assert near.max() > 0.5, (x, y)


def test_ball_indent_same_result_on_1_and_2_ranks(tmp_path):
    """The ffddm path (RAS + GMRES, the whole active set on every rank) gives the serial result."""
    recs = []
    for ranks in (1, 2):
        scene = load(WORKFLOWS / "ball-indent.toml", smoke=True)
        scene.geometry.h = 0.25
        scene.numerics.solver = "ffddm"
        scene.numerics.ranks = ranks
        scene.output.png = False
        from wendel.loop import run_scene

        root = run_scene(scene, WORKFLOWS / "ball-indent.toml", tmp_path / f"np{ranks}", progress=lambda *_: None)
        recs.append(summary(root)["last_increment"])
    a, b = recs
    assert a["ranks"] == 1 and b["ranks"] == 2
    assert a["newton_iterations"] == b["newton_iterations"]
    assert a["contact_active_nodes"] == b["contact_active_nodes"]
    assert b["contact_force"] == pytest.approx(a["contact_force"], rel=1e-8)
    assert b["plastic_volume"] == pytest.approx(a["plastic_volume"], rel=1e-8)


def test_study_plots_the_force_next_to_dealii(tmp_path):
    from wendel.results.study import study

    root = study(WORKFLOWS / "ball-indent.toml", levels=2, smoke=True, out=tmp_path / "s", progress=lambda *_: None)
    import csv

    with open(root / "study.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 1 and float(rows[0]["contact_force"]) > 0      # the finest level is the reference
    png = root / "contact_force_vs_runtime.png"
    assert png.is_file() and png.stat().st_size > 10_000
