"""The quasi-static loop: remeshing at a known increment, output across remeshes, resume after SIGKILL."""

import json
import os
import signal
import subprocess
import sys
import time

import meshio
import numpy as np
import pytest

from wendel.results import vtu as output
from wendel.loop import run

from conftest import WORKFLOWS

UPSETTING = (WORKFLOWS / "upsetting.toml").read_text()


def test_forced_remesh_at_a_known_increment_and_pvd_through_remeshes(tmp_path, scene_file):
    # quality threshold out of reach: the only remesh is the one asked after increment 2
    text = UPSETTING.replace("min_quality = 0.5", "min_quality = 0.01\nat = [2]")
    root = run(scene_file(text), smoke=True, out=tmp_path / "r", png=False, progress=lambda *_: None)
    s = json.loads((root / "summary.json").read_text())
    assert s["completed"]
    assert [r["after_increment"] for r in s["remeshes"]] == [2]
    rep = s["remeshes"][0]
    assert rep["residual_after_reequilibration"] < 1e-7 < rep["residual_after_transfer"]
    assert rep["new_elements"] != rep["old_elements"]
    assert abs(rep["integral_p_after"] - rep["integral_p_before"]) <= 0.05 * rep["integral_p_before"]
    assert 0 <= rep["yield_violation_after_transfer"] <= 1
    hist = (root / "history.csv").read_text().splitlines()
    header = hist[0].split(",")
    reeq = [r.split(",")[header.index("reequilibration")] for r in hist[1:]]
    assert reeq.index("1") == 2             # increment 3 re-equilibrates at the load factor of increment 2
    # every step of the PVD reads back; the mesh changes at the remesh and stays valid
    sizes = []
    for t, vtu in output.read_pvd(root / "results.pvd"):
        m = meshio.read(vtu)
        assert {"u", "vonMises", "p"} <= set(m.point_data) | set(m.cell_data)
        sizes.append(len(m.points))
    assert sizes[0] == sizes[1] != sizes[2] == sizes[-1]
    assert (root / "remesh" / "remesh-1.json").is_file()


def test_resume_after_sigkill_reproduces_the_uninterrupted_run(tmp_path, scene_file):
    path = scene_file(UPSETTING)
    full = run(path, smoke=True, out=tmp_path / "full", png=False, progress=lambda *_: None)
    cut = tmp_path / "cut"
    cmd = [sys.executable, "-m", "wendel.cli", "run", str(path), "--smoke", "--out", str(cut)]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.time() + 120
    while not (cut / "fem" / "inc-0003" / "done").exists():
        assert proc.poll() is None and time.time() < deadline, "the run ended before it could be killed"
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    resumed = run(None, resume=cut, progress=lambda *_: None)
    a = json.loads((full / "summary.json").read_text())
    b = json.loads((resumed / "summary.json").read_text())
    assert b["completed"] and b["increments"] == a["increments"]
    assert [r["after_increment"] for r in b["remeshes"]] == [r["after_increment"] for r in a["remeshes"]]
    last = f"inc-{a['increments']:04d}"
    ua = output.read_array(full / "fem" / last / "u_total.node.txt")
    ub = output.read_array(cut / "fem" / last / "u_total.node.txt")
    assert np.allclose(ua, ub, rtol=0, atol=1e-9 * np.abs(ua).max())
    ha = (full / "history.csv").read_text().splitlines()
    hb = (cut / "history.csv").read_text().splitlines()
    assert len(ha) == len(hb)
    assert [r.split(",")[:3] for r in ha] == [r.split(",")[:3] for r in hb]


ADAPTIVE = """
description = "thick-walled cylinder loaded in one step with adaptive increments"
[geometry]
builder = "ring"
r_inner = 1.0
r_outer = 1.3
h = 0.1
[material]
E = 70e9
nu = 0.3
[plasticity]
law = "linear"
sigma0 = 250e6
H = 1e9
[boundary.symmetry_x]
ux = 0.0
[boundary.symmetry_y]
uy = 0.0
[boundary.inner]
pressure = 100e6
[loading]
factors = [0.5, 0.74]
adaptive = true
[numerics]
newton_maxit = 5
[output]
png = false
"""


def test_adaptive_steps_cut_grow_and_land_on_the_targets(tmp_path, scene_file):
    root = run(scene_file(ADAPTIVE), out=tmp_path / "r", progress=lambda *_: None)
    rows = (root / "history.csv").read_text().splitlines()
    head = rows[0].split(",")
    lfs = [float(r.split(",")[head.index("load_factor")]) for r in rows[1:]]
    its = [int(r.split(",")[head.index("newton_iterations")]) for r in rows[1:]]
    assert 0.5 in lfs and lfs[-1] == 0.74                     # every target reached exactly
    assert len(lfs) > 2 and all(b > a for a, b in zip(lfs, lfs[1:]))
    steps = [b - a for a, b in zip([0.0] + lfs[:-1], lfs)]
    s = json.loads((root / "summary.json").read_text())
    assert s["step_cuts"] >= 1
    # after an easy increment the next attempted step is larger than the one just taken
    from wendel.loop import State, grow_step
    from wendel.scene import parse
    import tomllib

    scene = parse(tomllib.loads(ADAPTIVE))
    st = State(accepted=[(1, 0.1)], step=0.1)
    inc = tmp_path / "g" / "fem" / "inc-0001"
    inc.mkdir(parents=True)
    (inc / "record.json").write_text(json.dumps({"newton_iterations": 2}))
    from wendel.loop import RunFiles
    grow_step(scene, st, RunFiles(tmp_path / "g"))
    assert st.step == pytest.approx(0.15)
    (inc / "record.json").write_text(json.dumps({"newton_iterations": 9}))
    grow_step(scene, st, RunFiles(tmp_path / "g"))
    assert st.step == pytest.approx(0.15)                      # a hard increment does not grow it
    assert max(steps) <= 0.5 + 1e-12 and min(its) >= 1


def test_progress_heartbeat_reports_the_running_newton_iteration(tmp_path):
    from wendel.loop.progress import _Progress

    inc = tmp_path / "inc-0003"
    inc.mkdir()
    (inc / "newton.csv").write_text("increment,load_factor,iteration,residual,relative_residual\n"
                                    "3,0.5,0,1.0,1.0\n3,0.5,1,0.01,0.0123\n")
    lines = []
    _Progress(tmp_path, 3, 1, [0.5], lines.append)._heartbeat()
    assert lines and "increment 3 (load factor 0.5): Newton iteration 1, relative residual 1.23e-02" in lines[0]
