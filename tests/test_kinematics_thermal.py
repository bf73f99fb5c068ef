"""Heat conduction and thermal expansion under updated-Lagrangian kinematics (edp/lib/kinematics-thermal.idp).

Free thermal expansion (3D cube, plane-strain square, (r, z) cylinder): stress-free (plane strain: the
out-of-plane stress -E alpha dT) and the stretch exp(alpha dT) of the logarithmic strain (plane strain
exp((1 + nu) alpha dT)). Steady conduction through a block stretched to twice its length: the heat flow is
that of the current block, k dT A / L. Transient conduction with thermal expansion in a body rotating by
90 degrees: the temperatures of the non-rotating body. The small-strain thermo-mechanical scenes run with
updated-Lagrangian kinematics: the same answers to the order of the deformation.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from wendel.loop import run
from wendel.meshes import LABELS
from wendel.results import vtu as output

from conftest import WORKFLOWS, edit


def last(root: Path):
    """(record, cell fields, node fields) of the last increment of a run."""
    d = sorted((root / "fem").glob("inc-*"))[-1]
    cells = {f.name.removesuffix(".cell.txt"): output.read_array(f) for f in d.glob("*.cell.txt")}
    nodes = {f.name.removesuffix(".node.txt"): output.read_array(f) for f in d.glob("*.node.txt")}
    return json.loads((d / "record.json").read_text()), cells, nodes


def go(scene_file, text: str, tmp_path: Path, quiet, name: str, smoke: bool = False) -> Path:
    return run(scene_file(text, f"{name}.toml"), smoke=smoke, out=tmp_path / name, progress=quiet, png=False)


E, NU, ALPHA = 200e9, 0.3, 1e-4          # Pa, 1, 1/K
TREF, TD = 293.15, 1293.15               # K: alpha dT = 0.1, a stretch exp(0.1) = 1.105 (1 + alpha dT: 1.1)

MATERIAL = f"""
[material]
E = {E}                  # Pa
nu = {NU}                # 1

[kinematics]
kind = "updated-lagrangian"
"""
THERMAL = """
[thermal]
k = 50.0                 # W/m/K
rho = 7800.0             # kg/m^3
c = 460.0                # J/kg/K
alpha = {alpha}          # 1/K
T_ref = 293.15           # K
coupling = "{coupling}"
duration = {duration}    # s (0: steady)
"""
NUMERICS = """
[loading]
steps = {steps}

[numerics]
solver = "direct"
newton_tol = 1e-12

[output]
png = false
"""

# the plane-strain square on its symmetry planes (left, bottom)
SQUARE = """[geometry]
builder = "rectangle"
x = [0.0, 0.1]           # m
y = [0.0, 0.1]           # m
h = 0.05                 # m
[boundary.left]
ux = 0.0                 # m
[boundary.bottom]
uy = 0.0                 # m
"""
# steady: the outer edges (right, top) held at 1293.15 K, 2 increments
HOT_EDGES = ("[thermal.boundary.right]\ntemperature = 1293.15   # K\n"
             "[thermal.boundary.top]\ntemperature = 1293.15     # K\n" + NUMERICS.format(steps=2))

FREE = {
    # 3D cube on symmetry planes, transient: heated by a uniform source (1000 K in 1 s without the
    # Gough-Joule cooling), insulated, 4 increments, monolithic
    "3d": ("""description = "UL free thermal expansion, cube"
[geometry]
builder = "box"
x = [0.0, 0.1]           # m
y = [0.0, 0.1]           # m
z = [0.0, 0.1]           # m
h = 0.05                 # m
[boundary.left]
ux = 0.0                 # m
[boundary.front]
uy = 0.0                 # m
[boundary.bottom]
uz = 0.0                 # m
""" + MATERIAL + THERMAL.format(alpha=2e-5, coupling="monolithic", duration=1.0)
           + "source = 3.588e9           # W/m^3: rho c 1000 K / 1 s\n" + NUMERICS.format(steps=4), 3, 2e-5),
    # plane-strain square on symmetry planes, steady, every other edge at 1293.15 K, staggered
    "plane": ("""description = "UL free thermal expansion, plane strain"
""" + SQUARE + MATERIAL + THERMAL.format(alpha=ALPHA, coupling="staggered", duration=0.0)
              + HOT_EDGES, 2, ALPHA),
    # the same with perfect plasticity: sigma_zz = -E alpha dT would be 80 sigma0, so the body flows
    "plane-plastic": ("""description = "UL free thermal expansion, plane strain, perfectly plastic"
""" + SQUARE + """[plasticity]
law = "perfect"
sigma0 = 250e6           # Pa
""" + MATERIAL + THERMAL.format(alpha=ALPHA, coupling="monolithic", duration=0.0)
              + HOT_EDGES, 2, ALPHA),
    # (r, z) cylinder on its symmetry plane, steady, outer surface and top at 1293.15 K, monolithic
    "axi": ("""description = "UL free thermal expansion, (r, z) cylinder"
[geometry]
builder = "axi_rectangle"
r = [0.0, 0.1]           # m
z = [0.0, 0.1]           # m
h = 0.05                 # m
[elasticity]
plane = "axisymmetric"
[boundary.bottom]
uy = 0.0                 # m
""" + MATERIAL + THERMAL.format(alpha=ALPHA, coupling="monolithic", duration=0.0)
            + HOT_EDGES, 2, ALPHA),
}


@pytest.mark.parametrize("case", sorted(FREE))
def test_free_thermal_expansion_is_stress_free_and_stretches_by_the_exponential(tmp_path, scene_file, quiet, case):
    """A uniformly heated body on symmetry planes: every side stretched by exp(alpha dT) (plane strain: the
    in-plane sides by exp((1 + nu) alpha dT)) to 1e-8 relative, far from 1 + alpha dT; stresses round-off
    (plane strain: sigma_zz = -E alpha dT; perfectly plastic: sigma_zz = -sigma0 and the in-plane stretch
    exp(1.5 alpha dT - (1/2 - nu) sigma0 / E))."""
    text, dim, alpha = FREE[case]
    rec, cells, nodes = last(go(scene_file, text, tmp_path, quiet, case))
    T = nodes["T"]
    assert T.max() - T.min() < 1e-9 * T.max()                     # uniform
    dT = T.mean() - TREF
    assert dT > 500                                                # the run heated it
    stretch = math.exp(((1 + NU) if case == "plane" else 1.0) * alpha * dT)
    if case == "plane-plastic":     # sigma_zz = -sigma0, eps_zz = 0: the flow takes alpha dT - sigma0 / E off zz
        stretch = math.exp(1.5 * alpha * dT - (0.5 - NU) * 250e6 / E)
    pos = nodes["position"].reshape(-1, dim)
    size = pos.max(axis=0) - pos.min(axis=0)
    assert np.abs(size / (0.1 * stretch) - 1).max() < 1e-8, (size, stretch)
    linear = 1 + ((1 + NU) if case.startswith("plane") else 1.0) * alpha * dT
    assert abs(stretch - linear) > 1e-4                            # the test tells the two apart
    scale = E * alpha * dT
    names = ["stress_xx", "stress_yy", "stress_xy"] + (["stress_zz", "stress_xz", "stress_yz"] if dim == 3 else [])
    for n in names:
        assert np.abs(cells[n]).max() < 1e-10 * scale, (n, np.abs(cells[n]).max())
    if case == "plane":
        assert np.abs(cells["stress_zz"] / (-scale) - 1).max() < 1e-10
    if case == "plane-plastic":
        assert np.abs(cells["stress_zz"] / -250e6 - 1).max() < 1e-10
    if case == "axi":
        assert np.abs(cells["stress_zz"]).max() < 1e-10 * scale    # the hoop stress
    assert rec["energy_balance_error"] < 1e-10


STRETCH = """description = "UL steady conduction through a block stretched to twice its length"
[geometry]
builder = "rectangle"
x = [0.0, 1.0]           # m
y = [0.0, 0.5]           # m
h = 0.25                 # m
[boundary.left]
ux = 0.0                 # m
[boundary.bottom]
uy = 0.0                 # m
[boundary.right]
ux = 1.0                 # m at load factor 1: twice the length
""" + MATERIAL + THERMAL.format(alpha=0.0, coupling="monolithic", duration=0.0) + """
[thermal.boundary.left]
temperature = 400.0      # K
[thermal.boundary.right]
temperature = 300.0      # K
""" + NUMERICS.format(steps=4)


@pytest.mark.parametrize("case", ["plane", "axi", "3d"])
def test_conduction_through_a_stretched_block_is_that_of_the_current_block(tmp_path, scene_file, quiet, case):
    """Steady conduction between the ends of a block stretched from 1 m to 2 m (elastic, logarithmic strain,
    free lateral contraction): the heat into the hot end is k dT A / L of the current block to 1e-10 (plane
    strain A = the current height per unit thickness; (r, z) a cylinder along z, A = pi r^2); on the launch
    mesh it would be k dT A0 / L0, more than twice as much. 3D: a flux q = 1 kW/m^2 into the left end (per
    current area) and 300 K at the right end: the heat out of the right end is q A, the left end at
    300 K + q L / k (the surface stretch of Nanson's formula and the conduction on the current block)."""
    text = STRETCH
    hot, dim = "left", 2
    if case == "3d":
        text = edit(text, 'builder = "rectangle"\nx = [0.0, 1.0]           # m\ny = [0.0, 0.5]           # m\nh = 0.25',
                    'builder = "box"\nx = [0.0, 1.0]           # m\ny = [0.0, 0.5]           # m\n'
                    'z = [0.0, 0.5]           # m\nh = 0.5')
        text = edit(text, "[boundary.bottom]\nuy = 0.0", "[boundary.front]\nuy = 0.0                 # m\n"
                    "[boundary.bottom]\nuz = 0.0")
        text = edit(text, "[thermal.boundary.left]\ntemperature = 400.0      # K",
                    "[thermal.boundary.left]\nflux = 1000.0            # W/m^2")
        rec, cells, nodes = last(go(scene_file, text, tmp_path, quiet, case))
        pos = nodes["position"].reshape(-1, 3)
        ext = pos.max(axis=0) - pos.min(axis=0)
        assert abs(ext[0] - 2.0) < 1e-10 and ext[1] < 0.45
        q, area = 1000.0, ext[1] * ext[2]
        assert abs(rec[f"heat_in_{LABELS['right']}"] / (-q * area) - 1) < 1e-10
        T_left = nodes["T"][np.abs(pos[:, 0]) < 1e-12]
        assert np.abs(T_left / (300.0 + q * 2.0 / 50.0) - 1).max() < 1e-10
        return
    if case == "axi":
        text = edit(text, 'builder = "rectangle"\nx = [0.0, 1.0]           # m\ny = [0.0, 0.5]           # m',
                    'builder = "axi_rectangle"\nr = [0.0, 0.5]           # m\nz = [0.0, 1.0]           # m')
        text = edit(text, "[boundary.left]\nux = 0.0                 # m\n[boundary.bottom]\nuy = 0.0                 # m\n"
                    "[boundary.right]\nux = 1.0", "[elasticity]\nplane = \"axisymmetric\"\n[boundary.bottom]\n"
                    "uy = 0.0                 # m\n[boundary.top]\nuy = 1.0")
        text = edit(text, "[thermal.boundary.left]", "[thermal.boundary.bottom]")
        text = edit(text, "[thermal.boundary.right]", "[thermal.boundary.top]")
        hot = "bottom"
    rec, cells, nodes = last(go(scene_file, text, tmp_path, quiet, case))
    pos = nodes["position"].reshape(-1, dim)
    ext = pos.max(axis=0) - pos.min(axis=0)
    k, dT = 50.0, 100.0
    if case == "plane":
        length, area, area0 = ext[0], ext[1], 0.5
    else:
        length, area, area0 = ext[1], math.pi * ext[0] ** 2, math.pi * 0.25
    assert abs(length - 2.0) < 1e-10
    q = rec[f"heat_in_{LABELS[hot]}"]
    assert abs(q / (k * dT * area / length) - 1) < 1e-10, (q, k * dT * area / length)
    assert q < 0.5 * k * dT * area0 / 1.0                           # not the launch mesh's flow


ROTATING = """description = "UL transient conduction with thermal expansion in a square rotating by 90 degrees"
[geometry]
builder = "rectangle"
x = [-0.5, 0.5]          # m
y = [-0.5, 0.5]          # m
h = 0.25                 # m
[boundary.left]
rotation = 1.5707963267948966   # rad at load factor 1, about the centre
""" + MATERIAL + THERMAL.format(alpha=1.2e-5, coupling="{coupling}", duration=2000.0) + """
[thermal.boundary.left]
temperature = 500.0      # K
[thermal.boundary.right]
h = 100.0                # W/m^2/K
T_inf = 293.15           # K
""" + NUMERICS.format(steps=10)


@pytest.mark.parametrize("coupling", ["monolithic", "staggered"])
def test_heat_conduction_is_objective_in_a_rotating_body(tmp_path, scene_file, quiet, coupling):
    """A steel square heated on one edge (500 K) and cooled by convection on the opposite one for 2000 s,
    expanding (alpha dT up to 2.5e-3, Gough-Joule coupling on), its heated edge held and turned by 90 degrees
    in 10 increments: the nodal temperatures equal those of the same square held still to 1e-9 relative,
    the von Mises stress to 1e-7, the positions are the still ones rotated."""
    text = ROTATING.replace("{coupling}", coupling)
    turned = last(go(scene_file, text, tmp_path, quiet, "turned"))
    still = last(go(scene_file, text.replace("rotation = 1.5707963267948966", "rotation = 0.0"),
                    tmp_path, quiet, "still"))
    Tt, Ts = turned[2]["T"], still[2]["T"]
    assert Ts.max() - Ts.min() > 50
    assert np.abs(Tt - Ts).max() < 1e-9 * Ts.max(), np.abs(Tt - Ts).max()
    vt, vs = turned[1]["vonMises"], still[1]["vonMises"]
    assert np.abs(vt - vs).max() < 1e-7 * vs.max(), np.abs(vt - vs).max() / vs.max()
    pt, ps = turned[2]["position"].reshape(-1, 2), still[2]["position"].reshape(-1, 2)
    rot = np.array([[0.0, -1.0], [1.0, 0.0]])
    assert np.abs(ps @ rot.T - pt).max() < 1e-9


@pytest.mark.parametrize("scene", ["thermo-constrained.toml", "thermo-free.toml"])
def test_small_strain_thermal_scenes_run_alike_updated_lagrangian(tmp_path, scene_file, quiet, scene):
    """The workflows' thermo-mechanical cubes (100 K, alpha dT = 1.2e-3) with updated-Lagrangian kinematics:
    the constrained cube's mean stress as in small strain (-600 MPa) to 1e-10, the free cube's displacement
    that of small strain to the order of the strain (exp(alpha dT) - 1 against alpha dT: 6e-4 relative)
    and its stresses round-off."""
    text = (WORKFLOWS / scene).read_text()
    ss = last(go(scene_file, text, tmp_path, quiet, "ss", smoke=True))
    ul = last(go(scene_file, text + '\n[kinematics]\nkind = "updated-lagrangian"\n', tmp_path, quiet, "ul", smoke=True))
    aT = 1.2e-5 * 100.0
    if scene == "thermo-constrained.toml":
        for r in (ss, ul):
            assert abs(r[1]["mean_stress"].mean() / -600e6 - 1) < 1e-10
        assert np.abs(ul[1]["mean_stress"] - ss[1]["mean_stress"]).max() < 1e-10 * 600e6
    else:
        u_ss, u_ul = ss[2]["u"], ul[2]["u"]
        rel = np.abs(u_ul - u_ss).max() / np.abs(u_ss).max()
        assert abs(rel - (math.expm1(aT) - aT) / aT) < 1e-8, rel   # exactly the exponential's excess
        assert ul[1]["vonMises"].max() < 1e-9 * 200e9 * aT


def test_transient_coupled_square_agrees_with_small_strain_to_the_strain_order(tmp_path, scene_file, quiet):
    """The still square of the rotation test (monolithic, Gough-Joule on, strains up to ~1e-3) against the same
    scene in small strain: temperatures, displacements and von Mises stresses differ by less than 3e-3 of
    their range (measured: 8.5e-4, 8.3e-4, 7.1e-4), the order of the strain, not of the solution."""
    text = ROTATING.replace("{coupling}", "monolithic").replace("rotation = 1.5707963267948966", "rotation = 0.0")
    ul = last(go(scene_file, text, tmp_path, quiet, "ul"))
    ss = last(go(scene_file, edit(edit(text, 'kind = "updated-lagrangian"', 'kind = "small-strain"'),
                                  "rotation = 0.0", "ux = 0.0\nuy = 0.0"), tmp_path, quiet, "ss"))
    T_ul, T_ss = ul[2]["T"], ss[2]["T"]
    assert np.abs(T_ul - T_ss).max() < 3e-3 * (T_ss.max() - T_ss.min())
    assert np.abs(ul[2]["u"] - ss[2]["u"]).max() < 3e-3 * np.abs(ss[2]["u"]).max()
    assert np.abs(ul[1]["vonMises"] - ss[1]["vonMises"]).max() < 3e-3 * ss[1]["vonMises"].max()



def test_staggered_heat_without_thermal_stress_matches_the_monolithic_solution(tmp_path, scene_file, quiet):
    """With no thermal expansion (alpha = 0) the staggered step solves the heat equation and then the mechanics
    without the coupling block K_uT (zero; thermal.idp skips its assembly): the stretched block (plane strain),
    heated for 2000 s from its ends (not yet steady), has the monolithic coupling's temperatures and positions
    to the Newton tolerance, in as many Newton iterations."""
    text = STRETCH.replace("duration = 0.0    # s (0: steady)", "duration = 2000.0    # s")
    assert "duration = 2000.0" in text
    runs = {c: last(go(scene_file, text.replace('coupling = "monolithic"', f'coupling = "{c}"'), tmp_path, quiet, c))
            for c in ("monolithic", "staggered")}
    Tm, Ts = runs["monolithic"][2]["T"], runs["staggered"][2]["T"]
    assert Tm.max() - Tm.min() > 50 and np.abs(Tm - 300.0).max() > 5      # transient: not the linear profile
    assert np.abs(Tm - Ts).max() < 1e-8 * Tm.max(), np.abs(Tm - Ts).max() / Tm.max()
    pm, ps = runs["monolithic"][2]["position"], runs["staggered"][2]["position"]
    assert np.abs(pm - ps).max() < 1e-10
    # no coupling left out: the staggered step is the whole Newton step, as many iterations
    assert runs["staggered"][0]["newton_iterations"] == runs["monolithic"][0]["newton_iterations"]
