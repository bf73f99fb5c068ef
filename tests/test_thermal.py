"""Thermal module (edp/lib/thermal.idp): homogeneous thermoelastic checks, a manufactured (u, T) solution
with its observed rates, adiabatic heating of a Johnson-Cook bar, energy balance, bad input.

Tolerances: 1e-6 relative for the homogeneous checks (exact for P1 up to round-off), observed rates within
0.2 of the element order for the manufactured solution, energy balance within 1%.
"""

import csv
import json
import re

import numpy as np
import pytest

from wendel.results import vtu as output
from wendel.loop import run
from wendel.results.study import study

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
    xyz = output.read_vertices(root / "fem" / "vertices.txt")
    assert np.abs(u - ALPHA * DT * xyz).max() <= 1e-6 * ALPHA * DT * np.abs(xyz).max()   # strain alpha dT
    assert last["newton_iterations"] <= 2                # staggered: heat, then mechanics


def test_manufactured_coupled_solution_converges_at_the_element_order(tmp_path):
    root = study(WORKFLOWS / "thermo-mms.toml", levels=3, smoke=True, out=tmp_path / "study", progress=lambda *_: None)
    rows = list(csv.DictReader(open(root / "study.csv")))
    assert abs(float(rows[-1]["rate_h1"]) - 1.0) < 0.2      # u, P1: H1 ~ h
    assert abs(float(rows[-1]["rate_l2"]) - 2.0) < 0.2      # u: L2 ~ h^2
    last = [_last(root / f"level-{k}") for k in range(3)]
    for norm, order in (("l2", 2.0), ("h1", 1.0)):           # T, P1
        e = [r[f"error_T_{norm}"] / r[f"reference_T_{norm}"] for r in last]
        assert abs(np.log2(e[1] / e[2]) - order) < 0.2
    assert all(r["newton_iterations"] == 1 for r in last)  # monolithic Newton on a linear coupled problem
    assert all(r["energy_balance_error"] <= 0.01 for r in last)


def test_adiabatic_johnson_cook_bar(tmp_path):
    root = run(WORKFLOWS / "thermo-adiabatic-bar.toml", smoke=True, out=tmp_path / "r", png=False, progress=lambda *_: None)
    last = _last(root)
    rho, c, beta, A, B, n = 7830.0, 477.0, 0.9, 792e6, 510e6, 0.26
    p = last["max_plastic_strain"]
    assert p == pytest.approx(1.0, abs=1e-9)
    rise = last["max_temperature"] - 293.15
    assert last["max_temperature"] - last["min_temperature"] <= 1e-9 * rise     # homogeneous
    volume = 1.0
    assert rise == pytest.approx(beta / (rho * c) * last["plastic_work"] / volume, rel=1e-9)
    exact = beta / (rho * c) * (A * p + B * p ** (n + 1) / (n + 1))              # 288.4 K
    assert rise == pytest.approx(exact, rel=5e-3)                              # trapezoidal rule over 40 steps
    assert last["energy_balance_error"] <= 0.01
    assert last["jc_clipped_points"] == 0


@pytest.mark.parametrize("m", [1.0, 0.7])
def test_adiabatic_softening_is_solved_with_the_flow(tmp_path, scene_file, m):
    # the same bar with thermal softening (m = 1: about 19 % at the end; m = 0.7: steeper, infinite slope at Tr). The return mapping solves the heating
    # T = T_n + beta / (rho c) (sy_n + sy) dp / 2 with the flow (thermal.idp's thermAdPrepare, plasticity.idp's
    # plastYield), so the softening is in the tangent: Newton converges quadratically, 3 iterations per increment
    # (measured; 6 when T came from the previous trial, a fixed point), and every increment is the discrete
    # uniaxial-stress recursion: eps_k = sy / E + p_k, sy = (A + B p^n)(1 - ((T - Tr) / (Tm - Tr))^m) (measured
    # 6e-15 for m = 1)
    from scipy.optimize import brentq

    text = (WORKFLOWS / "thermo-adiabatic-bar.toml").read_text().replace("jc_m = 1000.0 ", f"jc_m = {m} ")
    root = run(scene_file(text, "softening.toml"), smoke=True, out=tmp_path / "r", png=False, progress=lambda *_: None)
    rows = list(csv.DictReader((root / "history.csv").open()))
    E_, rho, c, beta, A, B, n, Tr, Tm = 205e9, 7830.0, 477.0, 0.9, 792e6, 510e6, 0.26, 293.15, 1793.0
    p0, T0, s0 = 0.0, Tr, A
    for k, row in enumerate(rows, 1):
        eps = k / len(rows) * 1.0063512195121951

        def sigma(p):   # the yield stress at p with T(p, sigma) solved for sigma
            Y = A + B * p ** n

            def f(sg):
                T = T0 + beta / (rho * c) * (s0 + sg) / 2 * (p - p0)
                return sg - Y * (1 - min(max((T - Tr) / (Tm - Tr), 0.0), 1.0) ** m)
            return brentq(f, 0.0, Y, xtol=1e-6)

        p = brentq(lambda q: eps - sigma(q) / E_ - q, p0, eps, xtol=1e-15)
        s = sigma(p)
        T0, p0, s0 = T0 + beta / (rho * c) * (s0 + s) / 2 * (p - p0), p, s
        assert float(row["max_temperature"]) == pytest.approx(T0, rel=1e-10), k
        assert float(row["max_von_mises"]) == pytest.approx(s, rel=1e-10), k
        assert int(row["newton_iterations"]) <= 4, (k, row["newton_iterations"])
    assert s < 0.85 * (A + B * p ** n)                  # softened by more than 15 %


def test_adiabatic_without_plasticity_is_refused(tmp_path, scene_file):
    text = (WORKFLOWS / "thermo-free.toml").read_text().replace('coupling = "staggered"', 'coupling = "adiabatic"')
    with pytest.raises(ValueError, match=re.escape("it needs a [plasticity] block")):
        run(scene_file(text), smoke=True, out=tmp_path / "r", png=False, progress=lambda *_: None)


def test_steady_heat_without_temperature_boundary_is_refused(scene_file):
    from wendel.scene import SceneError, load

    text = (WORKFLOWS / "thermo-free.toml").read_text().split("[thermal.boundary.left]")[0] + "\n[loading]\nsteps = 1\n"
    with pytest.raises(SceneError, match="needs a temperature or convection boundary"):
        load(scene_file(text))


def test_heated_ball_on_elastic_block_energy_balance(tmp_path, scene_file):
    """thermo-indent without plasticity: contact heat from the tool, Gough-Joule heat, cold table."""
    text = (WORKFLOWS / "thermo-indent.toml").read_text()
    text = text[:text.index("[plasticity]")] + text[text.index("[contact]"):]
    root = run(scene_file(text), smoke=True, out=tmp_path / "r", png=False, progress=lambda *_: None)
    last = _last(root)
    assert last["heat_contact"] > 0 and last["contact_active_nodes"] > 0
    assert 293.15 < last["max_temperature"] < 800.0                  # below the tool temperature
    assert last["energy_balance_error"] <= 0.01
    stored = last["thermal_energy_change"]
    sources = last["heat_contact"] + last["heat_boundary"] + last["heat_thermoelastic"] + last["heat_plastic"]
    assert abs(stored - sources) <= 0.01 * abs(stored)


def test_monolithic_coupling_with_an_iterative_solver_is_refused_at_check(scene_file):
    from wendel.scene import SceneError, load

    text = (WORKFLOWS / "thermo-mms.toml").read_text()
    assert 'solver = "direct"' in text
    with pytest.raises(SceneError, match=r'monolithic.*needs numerics.solver = "direct", not \'cg\''):
        load(scene_file(text.replace('solver = "direct"', 'solver = "cg"')))
