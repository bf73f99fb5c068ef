"""Orthogonal cutting, FE part with heat (issue 17): conduction, Taylor-Quinney and frictional heat in the cut.

The steel scene with ``thermal.coupling = "monolithic"`` (heat equation on the current body, every boundary
insulated) cut 30 um in 6 increments on its 25 um mesh, remeshed every 2: the heat ledger must balance (stored
heat = Taylor-Quinney heat + the chip's share of the frictional work), the partition must be the scene's, the
hottest point must be at the rake face (frictional heat), and the remeshes must carry the nodal temperature.
Scenes that ask frictional heat without a heat equation, or a partition outside [0, 1], are refused naming the
file and the key."""

import csv
import json
import subprocess
import sys

import meshio
import numpy as np
import pytest

from wendel.cutting.fe_run import run_cut
from wendel.scene import load

from conftest import WORKFLOWS

STEEL = WORKFLOWS / "cutting-aisi1045.toml"


def test_fe_cut_with_conduction_and_frictional_heat(tmp_path):
    scene = load(STEEL, smoke=True)
    scene.geometry.model_extra["length"] = 1.2e-3     # m: a shorter block (the cut is 30 um)
    scene.cutting.cut_length = 0.03e-3                # m: 6 increments of 5 um, as in the full scene
    scene.loading.steps = 6
    scene.cutting.remesh_every = 2
    scene.thermal.coupling = "monolithic"
    root = run_cut(scene, STEEL, tmp_path / "cut", smoke=False, progress=lambda *_: None, frames=False)
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader((root / "cutting.csv").open())]
    last = rows[-1]
    assert last["tool_travel_m"] == pytest.approx(0.03e-3, rel=1e-9)
    # the heat ledger of the run (J for the width b): what is stored is what the plastic work and friction made
    plastic, chip, tool, stored = (last[k] for k in ("heat_plastic_J", "heat_friction_chip_J", "heat_friction_tool_J",
                                                     "heat_stored_J"))
    assert stored == pytest.approx(plastic + chip, rel=1e-6)
    assert chip / (chip + tool) == pytest.approx(scene.cutting.heat_to_chip, rel=1e-9)
    assert chip > 0.005 * plastic and plastic > 0
    hist = list(csv.DictReader((root / "history.csv").open()))
    assert all(float(h["energy_balance_error"]) < 1e-6 for h in hist)
    # the temperature is a nodal field (the heat equation's), and its hottest point is at the rake face: the
    # frictional heat of the secondary zone, hotter than the primary zone
    m = meshio.read(root / "vtu" / f"inc-{int(last['increment']):04d}.vtu")
    assert "T" in m.point_data and "T" not in m.cell_data
    assert last["max_T_secondary_K"] == pytest.approx(last["max_temperature_K"], rel=1e-12)
    assert last["max_T_secondary_K"] > last["max_T_primary_K"] > scene.thermal.T_ref
    assert last["max_temperature_K"] > scene.thermal.T_ref + 50
    # the remeshes carry the nodal temperature: its largest value and its integral over the body
    s = json.loads((root / "summary.json").read_text())
    assert len(s["remeshes"]) >= 2
    for k in (1, 2):
        r = json.loads((root / "remesh" / f"remesh-{k}.json").read_text())
        assert r["max_T_after"] == pytest.approx(r["max_T_before"], rel=0.03)
        assert r["integral_T_after"] == pytest.approx(r["integral_T_before"], rel=1e-3)
        assert r["residual_after_reequilibration"] < 1e-6
    summary = json.loads((root / "cutting.json").read_text())
    assert summary["thermal_coupling"] == "monolithic" and not summary["adiabatic"]
    assert summary["oxley"]["T_int_C"] > summary["oxley"]["T_AB_C"] > 25
    assert len(summary["zone_temperatures"]["cycle_means"]) >= 2


@pytest.mark.parametrize("edit, key", [
    ('heat_to_chip = 0.5 ', "cutting.heat_to_chip"),
    ('friction = 0.5 ', "cutting.frictional_heat"),
])
def test_bad_heat_in_a_cutting_scene_is_refused(tmp_path, edit, key):
    text = STEEL.read_text()
    assert edit in text
    if key == "cutting.heat_to_chip":
        text = text.replace(edit, "heat_to_chip = 1.5 ")                           # a share above 1
    else:
        text = text.replace(edit, "frictional_heat = true\n" + edit)           # with coupling = "adiabatic"
    bad = tmp_path / "bad-cut.toml"
    bad.write_text(text)
    p = subprocess.run([sys.executable, "-m", "wendel.cli", "check", str(bad)], capture_output=True, text=True)
    assert p.returncode == 2, p.stdout + p.stderr
    msg = p.stdout + p.stderr
    assert "bad-cut.toml" in msg and key in msg and "Traceback" not in msg
