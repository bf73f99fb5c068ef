"""A re-equilibration after a remesh has no time (dt = 0): a rate-dependent Johnson-Cook point keeps the rate factor
of its last step with time (``plastRfN`` in edp/lib/plasticity.idp, state file ``plast_rf.qp.txt``).

A homogeneous plane-strain JC block pulled at 5,000 /s and remeshed half-way: the transfer is exact, so the
re-equilibration must leave the stress and the plastic strain where they were (with the quasi-static factor 1 it
relaxed von Mises by the whole factor, 895 -> 804 MPa, and grew p by 0.00055: measured before the fix), and the
stress before it must carry the factor 1 + C ln(rate / rate0) (the rate is in play, so the check can fail)."""

import csv
import json
import math

import numpy as np
import pytest

from wendel.loop import run
from wendel.results import vtu

BLOCK = """description = "Rate-dependent Johnson-Cook block pulled in plane strain, remeshed half-way"
[geometry]
builder = "rectangle"
x = [0.0, 1.0e-3]
y = [0.0, 1.0e-3]
h = 2.5e-4
[material]
E = 205e9
nu = 0.29
[plasticity]
law = "johnson-cook"
jc_A = 553.1e6
jc_B = 600.8e6
jc_n = 0.234
jc_C = 0.0134
jc_rate0 = 1.0
jc_m = 1.0
jc_T_room = 298.15
jc_T_melt = 1733.15
load_time = 1.0e-5
[boundary.left]
ux = 0.0
[boundary.bottom]
uy = 0.0
[boundary.right]
ux = 5.0e-5
[loading]
steps = 10
[remesh]
at = [5]
indicator = ""
"""


def test_the_re_equilibration_keeps_the_rate_factor(tmp_path, scene_file):
    root = run(scene_file(BLOCK), smoke=False, out=tmp_path / "r", png=False, progress=lambda *_: None)
    rows = list(csv.DictReader((root / "history.csv").open()))
    k = [r["reequilibration"] for r in rows].index("1")
    before, reeq, after = rows[k - 1], rows[k], rows[k + 1]
    assert before["load_factor"] == reeq["load_factor"]
    vm0, vm1 = float(before["max_von_mises"]), float(reeq["max_von_mises"])
    p0, p1 = float(before["max_plastic_strain"]), float(reeq["max_plastic_strain"])
    assert vm1 == pytest.approx(vm0, rel=1e-9)
    assert p1 == pytest.approx(p0, rel=1e-9)
    assert float(after["max_von_mises"]) > vm0
    # the stress before the remesh is the JC flow stress with the rate factor of that increment's rate
    # (plane strain: von Mises = the flow stress at every point of the homogeneous block)
    A, B, n, C = 553.1e6, 600.8e6, 0.234, 0.0134
    dp = p0 - float(rows[k - 2]["max_plastic_strain"])
    rate = dp / (0.1 * 1.0e-5)
    factor = 1 + C * math.log(rate)
    assert rate > 1000 and factor > 1.09
    assert vm0 == pytest.approx((A + B * p0 ** n) * factor, rel=1e-6)
    # the factor is state: written with every increment and carried by the transfer onto the new mesh
    rf = vtu.read_array(root / "fem" / f"inc-{k:04d}" / "plast_rf.qp.txt")
    assert np.allclose(rf, factor, rtol=1e-9)
    remeshed = json.loads((root / "summary.json").read_text())["remeshes"][0]
    assert remeshed["after_increment"] == k


def test_an_adiabatic_re_equilibration_makes_no_heat(tmp_path):
    """The steel cut (adiabatic, timed) at smoke size remeshed every 2 increments: the re-equilibrations' plastic
    flow (the transfer's out-of-balance) heats nothing, so the heat ledger stands still across them, and it
    still balances; the increments with time heat."""
    from wendel.cutting.fe_run import run_cut
    from wendel.scene import load

    from conftest import WORKFLOWS
    steel = WORKFLOWS / "cutting-aisi1045.toml"
    scene = load(steel, smoke=True)
    scene.geometry.model_extra["length"] = 1.2e-3     # m: a shorter block (the cut is 30 um)
    scene.cutting.cut_length = 0.03e-3
    scene.loading.steps = 6
    scene.cutting.remesh_every = 2
    assert scene.thermal.coupling == "adiabatic"
    root = run_cut(scene, steel, tmp_path / "cut", smoke=False, progress=lambda *_: None, frames=False)
    rows = list(csv.DictReader((root / "history.csv").open()))
    reeq = [k for k, r in enumerate(rows) if r["reequilibration"] == "1"]
    assert len(reeq) == 2
    for k in reeq:
        for key in ("heat_plastic", "plastic_work"):
            assert float(rows[k][key]) == float(rows[k - 1][key])
    timed = [float(rows[k][key]) - float(rows[k - 1][key]) for k in range(1, len(rows)) if k not in reeq
             for key in ("heat_plastic",)]
    assert min(timed) > 0
    assert all(float(r["energy_balance_error"]) < 1e-9 for r in rows)
