"""Contact with heat and thermal expansion under updated-Lagrangian kinematics.

The contact heat acts on the current contact surface: the conductance of thermal.idp integrates over the
current face (Nanson's da, edp/lib/thermal.idp), and friction.idp's node masses are the current surface's
(the Tresca bound and the Coulomb cap are tractions on it). Thermal expansion works with the contact in the
current configuration (friction.idp): the (u, T) coupling block takes its rotated Newton rows.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from wendel.loop import run
from wendel.results import vtu as output

from conftest import WORKFLOWS

E, NU, ALPHA, DT = 200e9, 0.3, 1e-4, 1000.0      # Pa, 1, 1/K, K: alpha dT = 0.1
H_C, T_TOOL = 1e4, 1393.15                      # W/m^2/K, K (the body at 1293.15 K)

WALL = """description = "UL: a heated (r, z) cylinder expanding against a rigid wall, heat through the wall"
[geometry]
builder = "axi_rectangle"
r = [0.0, 0.1]           # m
z = [0.0, 0.1]           # m
h = 0.05                 # m
[elasticity]
plane = "axisymmetric"
[boundary.bottom]
uy = 0.0                 # m
[material]
E = 200e9                # Pa
nu = 0.3                 # 1
[kinematics]
kind = "updated-lagrangian"
[contact]
boundary = "top"
normal = "+y"
obstacle = "plane"
center = [0.0, 0.1]      # m: the wall touches the top face
[thermal]
k = 50.0                 # W/m/K
rho = 7800.0             # kg/m^3
c = 460.0                # J/kg/K
alpha = 1e-4             # 1/K
T_ref = 293.15           # K
coupling = "monolithic"
duration = 0.0           # s: steady
tool_temperature = 1393.15   # K, the wall
contact_conductance = 1e4    # W/m^2/K
[thermal.boundary.right]
temperature = 1293.15    # K
[thermal.boundary.top]
temperature = 1293.15    # K
[loading]
steps = 2
[numerics]
solver = "direct"
newton_tol = 1e-12
[output]
png = false
"""


def records(root: Path) -> list[dict]:
    return [json.loads((d / "record.json").read_text()) for d in sorted((root / "fem").glob("inc-*"))]


def test_heated_cylinder_against_a_wall_presses_and_takes_heat_on_its_current_face(tmp_path, scene_file, quiet):
    """A cylinder (radius 0.1 m) heated by dT = 1000 K between its base and a rigid wall, free radially: the
    logarithmic strain gives sigma_zz = -E alpha dT and the radius R exp((1 + nu) alpha dT), so the wall's force
    is E alpha dT pi R^2 exp(2 (1 + nu) alpha dT) (to 1e-10; measured 1e-15), and the heat through the wall per
    (steady) increment h_c (T_tool - T) times the current face's area (to 1e-10; the launch face's is 23 %
    smaller: the conductance used it before)."""
    root = run(scene_file(WALL, "wall.toml"), out=tmp_path / "wall", progress=quiet, png=False)
    recs = records(root)
    d = sorted((root / "fem").glob("inc-*"))[-1]
    T = output.read_array(d / "T.node.txt")
    assert np.abs(T - (293.15 + DT)).max() < 1e-9 * T.max()
    a = ALPHA * DT
    radius = 0.1 * math.exp((1 + NU) * a)
    pos = output.read_array(d / "position.node.txt").reshape(-1, 2)
    assert pos[:, 0].max() == pytest.approx(radius, rel=1e-10)
    area = math.pi * radius ** 2
    assert recs[-1]["contact_force"] == pytest.approx(E * a * area, rel=1e-10)
    heat = recs[-1]["heat_contact"] - recs[-2]["heat_contact"]        # W: steady increments add up
    assert heat == pytest.approx(H_C * (T_TOOL - T.mean()) * area, rel=1e-10)
    assert heat / (H_C * (T_TOOL - T.mean()) * math.pi * 0.1 ** 2) - 1 > 0.2
    assert recs[-1]["energy_balance_error"] < 1e-10


STRIP_TOP = """[boundary.top]
ux = 0.0                 # m
uy = 0.0                 # m"""


def test_tresca_frictional_heat_acts_on_the_current_contact_area(tmp_path, scene_file, quiet):
    """heat-strip.toml (Tresca, tau = 1 MPa, half the work into the strip) with updated-Lagrangian kinematics and
    its top stretched along x by u = lf G X (10 % at load factor 1, 20 % at the end of the drag): the frictional
    work of each drag increment is tau sum m_p |v_p| over the slipping nodes with m_p the lumped masses of the
    CURRENT bottom face (from the written positions; to 1e-9, measured 1.4e-11); with the launch face's masses it is 8-15 %
    smaller. The record's contact area is the current one (1e-12, measured 2e-16); the heat entering the strip
    is half the work (energy, 1e-6)."""
    text = (WORKFLOWS / "heat-strip.toml").read_text()
    assert STRIP_TOP in text
    text = text.replace(STRIP_TOP, "[boundary.top]\ngradient = [0.1, 0.0, 0.0, 0.0]   # 1 per unit load factor\n")
    text += '\n[kinematics]\nkind = "updated-lagrangian"\n'
    root = run(scene_file(text, "strip.toml"), smoke=True, out=tmp_path / "strip", progress=quiet, png=False)
    X = output.read_vertices(root / "fem" / "vertices.txt")[:, :2]
    bottom = np.where(np.abs(X[:, 1]) < 1e-12)[0]
    bottom = bottom[np.argsort(X[bottom, 0])]

    def masses(p):          # lumped P1 masses of the polyline p (half of each edge to each end)
        ds = np.hypot(*np.diff(p, axis=0).T)
        m = np.zeros(len(p))
        m[:-1] += ds / 2
        m[1:] += ds / 2
        return m

    dirs = sorted((root / "fem").glob("inc-*"))
    recs = records(root)
    checked = 0
    for k in range(1, len(dirs)):
        pos = output.read_array(dirs[k] / "position.node.txt").reshape(-1, 2)
        state = output.read_array(dirs[k] / "friction_state.node.txt")[bottom]
        slip = np.abs(output.read_array(dirs[k] / "friction_slip.node.txt")[bottom])
        m, m0 = masses(pos[bottom]), masses(X[bottom])
        sliding = state > 1.5
        assert sliding.sum() >= 4
        work = recs[k]["friction_work"] - recs[k - 1]["friction_work"]
        assert work == pytest.approx(1e6 * np.sum(m[sliding] * slip[sliding]), rel=1e-9)
        assert 1e6 * np.sum(m0[sliding] * slip[sliding]) < 0.95 * work
        assert recs[k]["contact_area"] == pytest.approx(m[state > 0.5].sum(), rel=1e-12)
        checked += 1
    assert checked >= 10
    last = recs[-1]
    assert last["heat_contact"] == pytest.approx(0.5 * last["friction_work"], rel=1e-6)
    assert last["thermal_energy_change"] == pytest.approx(0.5 * last["friction_work"], rel=1e-6)


def test_thermo_indent_with_thermal_expansion_under_ul_agrees_with_small_strain_at_small_depth(tmp_path, scene_file,
                                                                                               quiet):
    """thermo-indent.toml (a heated ball, alpha = 1.2e-5 /K, contact conductance, Johnson-Cook) pressed 0.3 mm
    instead of 3 mm (smoke mesh): under updated-Lagrangian kinematics its ball takes friction.idp's contact with
    thermal expansion (refused before); contact heat, plastic heat, force and peak temperature agree with
    small strain (contact.idp) to 2 % (measured 0.94 %, 0.20 %, 0.43 %, 0.16 %: the order of the strains, plastic
    up to 0.028); both energy balances close. Small strain through friction.idp (friction law none, so the gap in
    the current configuration, with thermal expansion: FreeFEM refused it before) agrees with contact.idp to 1 %
    (measured 0.21 % force, 1e-4 contact heat; without the coupling block's rotated rows its Newton method gave NaN
    at the first increment and the run failed)."""
    text = (WORKFLOWS / "thermo-indent.toml").read_text()
    old = "displacement = -0.003    # m, downwards at load factor 1"
    assert old in text and "alpha = 1.2e-5" in text
    text = text.replace(old, "displacement = -0.0003   # m, downwards at load factor 1")
    friction = text.replace("displacement = -0.0003", 'friction = { law = "none" }\ndisplacement = -0.0003')
    last = {}
    for name, kind, body in (("ss", "small-strain", text), ("ul", "updated-lagrangian", text),
                             ("ss-friction", "small-strain", friction)):
        path = scene_file(body + f'\n[kinematics]\nkind = "{kind}"\n', f"{name}.toml")
        root = run(path, smoke=True, out=tmp_path / name, progress=quiet, png=False)
        last[name] = records(root)[-1]
        assert last[name]["energy_balance_error"] < 1e-9
    ul, ss, ssf = last["ul"], last["ss"], last["ss-friction"]
    assert "friction_work" in ul and "friction_work" in ssf and "friction_work" not in ss     # the contact modules
    assert ul["heat_contact"] > 1e4 and ul["heat_plastic"] > 100
    for key in ("heat_contact", "heat_plastic", "contact_force", "max_temperature"):
        assert ul[key] == pytest.approx(ss[key], rel=0.02), key
        assert ssf[key] == pytest.approx(ss[key], rel=0.01), key
