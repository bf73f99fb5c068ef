"""Thermal module (edp/lib/thermal.idp): homogeneous thermoelastic checks, a manufactured (u, T) solution
with its observed rates, adiabatic heating of a Johnson-Cook bar, energy balance, bad input.

Tolerances: 1e-6 relative for the homogeneous checks (exact for P1 up to round-off), observed rates within
0.2 of the element order for the manufactured solution, energy balance within 1%.
"""

import csv
import json

import numpy as np
import pytest

from wendel import output
from wendel.freefem import FreeFemError
from wendel.run import run
from wendel.study import study

from conftest import WORKFLOWS

E, NU, ALPHA, DT = 200e9, 0.3, 1.2e-5, 100.0


def _last(root):
    return json.loads((root / "summary.json").read_text())["last_increment"]


def test_constrained_block_heated_uniformly(tmp_path):
    root = run(WORKFLOWS / "thermo-constrained.toml", smoke=True, out=tmp_path / "r", png=False, progress=lambda *_: None)
    last = _last(root)
    exact = -E * ALPHA * DT / (1 - 2 * NU)           # sigma = -3 K alpha dT, hydrostatic
    assert abs(last["mean_stress_min"] - exact) <= 1e-6 * abs(exact)
    assert abs(last["mean_stress_max"] - exact) <= 1e-6 * abs(exact)
    assert last["max_von_mises"] <= 1e-6 * abs(exact)
    assert last["max_displacement"] <= 1e-12
    assert last["min_temperature"] == pytest.approx(393.15, rel=1e-12)
    assert last["energy_balance_error"] <= 0.01


def test_free_expansion(tmp_path):
    root = run(WORKFLOWS / "thermo-free.toml", smoke=True, out=tmp_path / "r", png=False, progress=lambda *_: None)
    last = _last(root)
    scale = E * ALPHA * DT
    assert max(abs(last["mean_stress_min"]), abs(last["mean_stress_max"]), last["max_von_mises"]) <= 1e-6 * scale
    u = output.read_array(root / "fem" / "inc-0001" / "u.node.txt").reshape(-1, 3)
    with open(root / "fem" / "vertices.txt") as f:
        xyz = np.loadtxt(f, skiprows=1)
    assert np.abs(u - ALPHA * DT * xyz).max() <= 1e-6 * ALPHA * DT * np.abs(xyz).max()   # strain alpha dT
    assert last["newton_iterations"] <= 2                # staggered: heat, then mechanics
