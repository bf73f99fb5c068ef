"""Drilling in the axisymmetric (r, z) model: the drilled-section builder in the removal loop (real gmsh + FreeFEM)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from wendel.loop import run
from wendel.meshes import drilling as D

from conftest import IRON, IRON_THERMAL, drill, drill_table

R, ANGLE = 0.002, 118.0

RZ_SCENE = """
description = "test: drilling a cylinder, axisymmetric (r, z)"
[geometry]
builder = "drilled-section"
radius = 0.008           # m
height = 0.012           # m
h = 0.003                # m
[elasticity]
plane = "axisymmetric"
""" + IRON + """[boundary.bottom]
ux = 0.0                 # m
uy = 0.0                 # m
[thermal]
""" + IRON_THERMAL + """coupling = "monolithic"
[thermal.boundary.top]
h = 10.0                 # W/m^2/K
T_inf = 293.15           # K
[thermal.boundary.outer]
h = 10.0                 # W/m^2/K
T_inf = 293.15           # K
[numerics]
solver = "direct"
""" + drill_table(0.0005)


def _drill(tmp_path, extra, name="rz"):
    return drill(tmp_path, RZ_SCENE, extra, name)


def test_rz_drilling_energy_identity_and_removed_volume(tmp_path):
    """(r, z): four removal steps (remesh + conservative transfer each) and cooling to ambient. Heat in = heat in
    the body + chips - convection within 1 %; the removed volume of each step (volumes of revolution) is the
    analytic bore volume to round-off (straight profile edges); no stress left after cooling."""
    root, dr = _drill(tmp_path, "depth = 0.008\nsteps = 4\ncooling = 1e6\ncooling_steps = 1\nbore_h = 50.0\n"
                                "thrust = 100.0\n[[drilling.probes]]\nname = \"tc\"\nposition = [0.0, 0.003, 0.009]  # m")
    e = dr["energy"]
    assert e["chips_heat"] > 0.02 * e["heat_in"]
    assert e["convection"] < 0
    assert e["balance_error"] < 0.01
    for k in (2, 3, 4):
        rep = json.loads((root / "remesh" / f"remesh-{k:03d}.json").read_text())
        removed = rep["measure_old"] - rep["measure_new"]
        exact = D.bore_volume(rep["depth_new"], R, ANGLE) - D.bore_volume(rep["depth_old"], R, ANGLE)
        assert removed == pytest.approx(exact, rel=1e-9)
        assert rep["nodes_outside_old_mesh"] == 0          # straight edges: the new section lies in the old
    # the thermocouple at r = 3 mm, 3 mm deep, 1 mm from the wall: warmed, then back near ambient
    peak = dr["probes_peak"]["tc"]
    assert 293.5 < peak < 400.0
    profiles = json.loads((root / "drilling.json").read_text())["profiles"]
    hot, cold = profiles[-2], profiles[-1]
    assert cold["kind"] == "cool" and hot["kind"] == "drill"
    scale = np.nanmax(np.abs(hot["hoop_stress"]))
    assert scale > 1e6
    assert np.nanmax(np.abs(cold["hoop_stress"])) < 1e-3 * scale
    assert np.nanmax(hot["diameter_error"]) > 0          # the hot wall expands the bore
    assert np.nanmax(np.abs(cold["diameter_error"])) < 1e-3 * np.nanmax(np.abs(hot["diameter_error"]))


def test_rz_drilling_without_removal_keeps_energy_to_1e_6(tmp_path):
    """(r, z): a drill dwelling at a fixed depth (no removal, the mesh stays): energy identity below 1e-6,
    and the heat put in is q x the area of revolution of the bore bottom (the cone's, 2 pi r ds)."""
    root, dr = _drill(tmp_path, "depth = 0.003\nstart_depth = 0.003\ndwell = 0.5\ndwell_steps = 2\n"
                                "wall_fraction = 0.0\nthrust = 0.0")
    e = dr["energy"]
    assert e["chips_heat"] == 0.0
    assert e["balance_error"] < 1e-6
    assert e["heat_in"] == pytest.approx(0.3 * 2 * math.pi * 2000.0 / 60 * 1.0 * 0.5, rel=1e-12)


def test_killed_drilling_run_resumes_to_the_same_result(tmp_path):
    """A drilling run killed (SIGKILL, its whole process group) after its second removal step: `wendel run
    --resume` goes on after the last completed step (kept in drilling-state.json; those steps are not computed
    again) and ends with the result of an uninterrupted run."""
    import os
    import signal
    import subprocess
    import sys
    import time

    from wendel.freefem import ROOT

    extra = "depth = 0.008\nsteps = 4\ncooling = 1e6\ncooling_steps = 1"
    _, ref = _drill(tmp_path, extra, name="ref")
    scene = tmp_path / "k.toml"
    scene.write_text(RZ_SCENE.format(extra=extra))
    out = tmp_path / "killed"
    proc = subprocess.Popen([sys.executable, "-m", "wendel.cli", "run", str(scene), "--out", str(out)],
                            cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.time() + 120
    state = out / "drilling-state.json"
    while not (state.is_file() and json.loads(state.read_text())["done"] >= 2) and proc.poll() is None \
            and time.time() < deadline:
        time.sleep(0.02)
    assert proc.poll() is None, "the run ended before it could be killed"
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done = json.loads(state.read_text())["done"]
    assert 2 <= done < 4
    assert not (out / "summary.json").is_file() or "drilling" not in json.loads((out / "summary.json").read_text())
    kept = {d.name: (d / "record.json").stat().st_mtime_ns for d in (out / "fem").glob("inc-*")
            if int(d.name[4:]) <= done and (d / "record.json").is_file()}
    assert len(kept) == done
    said = []
    assert run(None, resume=out, progress=said.append) == out.resolve()
    assert any(f"resuming after removal step {done} of 4" in line for line in said)
    for name, mtime in kept.items():          # the completed steps were not computed again
        assert (out / "fem" / name / "record.json").stat().st_mtime_ns == mtime
    got = json.loads((out / "summary.json").read_text())["drilling"]
    for k in ("heat_in", "thermal_energy_change", "chips_heat", "convection"):
        assert got["energy"][k] == pytest.approx(ref["energy"][k], rel=1e-12, abs=1e-12)
    assert got["bore"]["diameter_error_after"] == pytest.approx(ref["bore"]["diameter_error_after"], rel=1e-9)
