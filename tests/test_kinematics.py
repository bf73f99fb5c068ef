"""Updated-Lagrangian kinematics (edp/lib/kinematics.idp): rigid rotation, plane-strain tension and
compression to large strain, elastic and perfectly plastic simple shear, the mesh-tangling guard.

Every case is homogeneous, so any mesh is exact and the references are closed forms or a material point.
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


def increments(root: Path):
    """(record, cell fields, node fields) of every increment of a run, in order."""
    out = []
    for d in sorted((root / "fem").glob("inc-*")):
        rec = json.loads((d / "record.json").read_text())
        cells = {f.name.removesuffix(".cell.txt"): output.read_array(f) for f in d.glob("*.cell.txt")}
        nodes = {f.name.removesuffix(".node.txt"): output.read_array(f) for f in d.glob("*.node.txt")}
        out.append((rec, cells, nodes))
    return out


def run_scene(scene_file, text: str, tmp_path: Path, quiet, smoke: bool = False, name: str = "run") -> Path:
    return run(scene_file(text, f"{name}.toml"), smoke=smoke, out=tmp_path / name, progress=quiet, png=False)


def material_point(loads, axis: int, E: float, nu: float, sigma0: float, H: float):
    """Plane-strain von Mises with linear hardening under a logarithmic strain ln(1 + lf) along ``axis``,
    the other in-plane stress zero: the stresses per load factor (backward-Euler radial return, the
    update the finite elements make at each increment; homogeneous and coaxial, so no rotation)."""
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    kappa = lam + 2 * mu / 3
    epsp, p = np.zeros(3), 0.0          # plastic strain xx, yy, zz; equivalent plastic strain

    def update(eps, epsp, p):
        ee = eps - epsp
        tr = ee.sum()
        s = 2 * mu * (ee - tr / 3)
        q = math.sqrt(1.5) * np.linalg.norm(s)
        dp = max(q - (sigma0 + H * p), 0.0) / (3 * mu + H)
        if dp > 0:
            epsp = epsp + 1.5 * dp * s / q
            s = s * (1 - 3 * mu * dp / q)
        return s + kappa * tr, epsp, p + dp

    out, lat = [], 0.0
    other = 1 - axis
    for lf in loads:
        eps = np.zeros(3)
        eps[axis] = math.log(1 + lf)
        for _ in range(60):             # Newton (secant slope) on the free lateral strain: sigma_other = 0
            eps[other] = lat
            sig, _, _ = update(eps, epsp, p)
            eps2 = eps.copy()
            eps2[other] = lat + 1e-9
            slope = (update(eps2, epsp, p)[0][other] - sig[other]) / 1e-9
            step = sig[other] / slope
            lat -= step
            if abs(step) < 1e-15:
                break
        eps[other] = lat
        sig, epsp, p = update(eps, epsp, p)
        out.append((sig, p, lat))
    return out


@pytest.mark.parametrize("scene, steps, dim", [("ul-rotation.toml", 20, 2), ("ul-rotation-3d.toml", 10, 3)])
def test_rigid_rotation_of_a_prestressed_block(tmp_path, quiet, scene, steps, dim):
    """90 degrees (2D square; 3D cube about z): the strain and stress tensors rotate with the body, their
    invariants stay (1e-8 relative), the points are the rotated ones."""
    root = run(WORKFLOWS / scene, out=tmp_path / "rot", progress=quiet, png=False)
    e0 = np.zeros((3, 3))
    e0[:2, :2] = [[1e-3, 3e-4], [3e-4, -2e-4]]
    incs = increments(root)
    assert len(incs) == steps
    first = incs[0][1]
    inv0 = [(first["stress_xx"] + first["stress_yy"] + first["stress_zz"]).mean(), first["vonMises"].mean()]
    comps = {"xx": (0, 0), "yy": (1, 1), "xy": (0, 1)}
    if dim == 3:
        comps.update({"zz": (2, 2), "xz": (0, 2), "yz": (1, 2)})
    for rec, cells, nodes in incs:
        th = rec["load_factor"] * math.pi / 2
        R = np.array([[math.cos(th), -math.sin(th), 0], [math.sin(th), math.cos(th), 0], [0, 0, 1]])
        e = R @ e0 @ R.T
        for key, (i, j) in comps.items():
            assert np.abs(cells[f"strain_{key}"] - e[i, j]).max() < 1e-12, (rec["increment"], key)
        trace = cells["stress_xx"] + cells["stress_yy"] + cells["stress_zz"]
        assert np.abs(trace / inv0[0] - 1).max() < 1e-8
        assert np.abs(cells["vonMises"] / inv0[1] - 1).max() < 1e-8
        pos = nodes["position"].reshape(-1, dim)
        X = pos - nodes["u_total"].reshape(-1, dim)
        assert np.abs(pos - X @ R[:dim, :dim].T).max() < 1e-12
    assert inv0[1] > 1e8            # the prestress is there (Pa)


def test_stress_free_rotation_stays_stress_free_and_small_strain_does_not(scene_file, tmp_path, quiet):
    text = (WORKFLOWS / "ul-rotation.toml").read_text()
    text = text.replace("initial_strain = [1e-3, -2e-4, 3e-4]", "initial_strain = [0.0, 0.0, 0.0]")
    root = run_scene(scene_file, text, tmp_path, quiet, smoke=True, name="free")
    worst = max(np.abs(c["vonMises"]).max() for _, c, _ in increments(root))
    assert worst < 1e-3                     # Pa, with E = 200 GPa and displacements of 1 m
    small = text.replace('kind = "updated-lagrangian"', 'kind = "small-strain"').replace(
        "initial_strain = [0.0, 0.0, 0.0]   # 1, tensor components xx, yy, xy: a homogeneous prestress", "")
    root = run_scene(scene_file, small, tmp_path, quiet, smoke=True, name="small")
    assert increments(root)[-1][1]["vonMises"].max() > 1e10     # rotation taken as strain


@pytest.mark.parametrize("scene, axis, reaction, lateral, remesh", [
    ("ul-tension.toml", 0, "reaction_x_2", 1, False),      # 100 % nominal tension, force on the right end
    ("ul-compression.toml", 1, "reaction_y_4", 0, False),  # 50 % height, force on the top platen
    ("ul-tension.toml", 0, "reaction_x_2", 1, True),       # remeshed after increment 5 (finer mesh)
    ("ul-compression.toml", 1, "reaction_y_4", 0, "fbar"),  # F-bar (kinematics.volumetric): homogeneous, the same
])
def test_homogeneous_tension_and_compression_to_large_strain(scene_file, tmp_path, quiet, scene, axis, reaction,
                                                            lateral, remesh):
    """Logarithmic strain exact (1e-10); Cauchy stress on the material-point curve (1e-8); on the yield surface
    sigma_y(p) = sigma0 + H p (1e-10); end force = stress x current section (1e-8). With a remesh the new
    mesh is made of the current configuration and the state carries over."""
    text = (WORKFLOWS / scene).read_text()
    if remesh == "fbar":
        text = text.replace('kind = "updated-lagrangian"', 'kind = "updated-lagrangian"\nvolumetric = "fbar"')
        assert 'volumetric = "fbar"' in text
        remesh = False
    if remesh:      # at the smoke size (10 increments; one launch per increment when remeshing)
        text = text.replace("[output]", "[remesh]\nat = [5]\nh = 0.05\n\n[output]")
    root = run(scene_file(text, "s.toml"), smoke=remesh, out=tmp_path / "r", progress=quiet, png=False)
    incs = increments(root)
    if remesh:
        assert len(incs) == 11 and incs[5][0]["elements"] > 2 * incs[4][0]["elements"]
        points, _ = output.read_mesh(root / "meshes" / "mesh-1.msh", 2)
        assert np.ptp(points[:, 0]) == pytest.approx(1.5, rel=1e-12)     # the current length at 50 %
    loads = [rec["load_factor"] * (1.0 if axis == 0 else -0.5) for rec, _, _ in incs]
    ref = material_point(loads, axis, 70e9, 0.3, 250e6, 1e9)
    names = ["stress_xx", "stress_yy"]
    for (rec, cells, nodes), nominal, (sig, p, lat) in zip(incs, loads, ref):
        s = cells[names[axis]]
        assert np.abs(cells[["strain_xx", "strain_yy"][axis]] - math.log(1 + nominal)).max() < 1e-10
        assert np.abs(s / sig[axis] - 1).max() < 1e-8, (rec["increment"], s.mean(), sig[axis])
        assert np.abs(cells[names[lateral]]).max() < 1e-8 * abs(sig[axis])
        assert np.abs(cells["p"] / p - 1).max() < 1e-8
        assert np.abs(cells["vonMises"] / (250e6 + 1e9 * cells["p"]) - 1).max() < 1e-10
        section = np.ptp(nodes["position"].reshape(-1, 2)[:, lateral])          # current width (m)
        assert abs(abs(rec[reaction]) / (abs(s.mean()) * section) - 1) < 1e-8
    assert abs(loads[-1]) in (1.0, 0.5)


@pytest.mark.parametrize("top, volumetric", [(1.0, "cell"), (-0.5, "cell"), (1.0, "fbar")])
def test_uniaxial_tension_and_compression_3d_on_the_closed_form_curve(scene_file, tmp_path, quiet, top, volumetric):
    """3D cube, frictionless ends, linear hardening: Cauchy stress against log strain on
    sigma = sigma0 + E H / (E + H) (|eps| - sigma0 / E) (1e-10), lateral stress 0, the end force equals
    sigma_y(eps) times the current section (1e-10). 100 % nominal tension, compression to 50 % height, and
    the tension with F-bar (kinematics.volumetric = "fbar": homogeneous, so the same closed form)."""
    E, H, s0 = 70e9, 1e9, 250e6
    text = (WORKFLOWS / "ul-tension-3d.toml").read_text().replace("uz = 1.0 ", f"uz = {top!r} ")
    text = text.replace('kind = "updated-lagrangian"', f'kind = "updated-lagrangian"\nvolumetric = "{volumetric}"')
    assert f'volumetric = "{volumetric}"' in text
    root = run(scene_file(text, "t3.toml"), smoke=True, out=tmp_path / "t3", progress=quiet, png=False)
    incs = increments(root)
    assert len(incs) == 10
    for rec, cells, nodes in incs:
        e = math.log(1 + top * rec["load_factor"])
        ref = math.copysign(E * abs(e) if E * abs(e) < s0 else s0 + E * H / (E + H) * (abs(e) - s0 / E), e)
        assert np.abs(cells["strain_zz"] - e).max() < 1e-12
        assert np.abs(cells["stress_zz"] / ref - 1).max() < 1e-10, (rec["increment"], cells["stress_zz"].mean(), ref)
        for k in ("stress_xx", "stress_yy", "stress_xy", "stress_xz", "stress_yz"):
            assert np.abs(cells[k]).max() < 1e-8 * abs(ref)
        pos = nodes["position"].reshape(-1, 3)
        section = np.ptp(pos[:, 0]) * np.ptp(pos[:, 1])
        assert rec["reaction_z_4"] / (ref * section) == pytest.approx(1.0, abs=1e-10)


def test_elastic_simple_shear_follows_the_jaumann_rate(tmp_path, quiet):
    """gamma = 4: sigma_xy = G sin(gamma), sigma_xx = -sigma_yy = G (1 - cos(gamma)) (hypoelastic, Jaumann),
    second order in the shear strain increment."""
    G = 200e9 / 2.6
    err = {}
    for smoke, dg in ((True, 0.1), (False, 0.05)):
        root = run(WORKFLOWS / "ul-shear.toml", smoke=smoke, out=tmp_path / f"s{smoke}", progress=quiet, png=False)
        e = 0.0
        for rec, cells, _ in increments(root):
            g = 4.0 * rec["load_factor"]
            e = max(e, np.abs(cells["stress_xy"] / G - math.sin(g)).max(),
                    np.abs(cells["stress_xx"] / G - (1 - math.cos(g))).max(),
                    np.abs(cells["stress_yy"] / G + (1 - math.cos(g))).max())
        err[dg] = e
    assert err[0.05] < 2e-3
    assert 3.0 < err[0.1] / err[0.05] < 5.0      # second order


def test_perfectly_plastic_simple_shear_stays_at_the_shear_yield_stress(tmp_path, quiet):
    """gamma = 5 in steps of 0.1: after yielding sigma_xy = k = sigma0 / sqrt(3) within dgamma^2 / 4 and
    sigma_xx / k within dgamma (the lag of the return mapping; the Jaumann limit is k / G)."""
    k, dg = 250e6 / math.sqrt(3), 0.1
    root = run(WORKFLOWS / "ul-shear-plastic.toml", smoke=True, out=tmp_path / "sp", progress=quiet, png=False)
    incs = increments(root)
    assert 5.0 * incs[-1][0]["load_factor"] == pytest.approx(5.0)
    for rec, cells, _ in incs:
        if 5.0 * rec["load_factor"] < 0.2 - 1e-9:
            continue
        assert np.abs(cells["stress_xy"] / k - 1).max() < dg ** 2 / 4
        assert np.abs(cells["stress_xx"] / k).max() < dg
        assert np.abs(cells["vonMises"] / 250e6 - 1).max() < 1e-10
    # p grows as the plastic shear: gamma_p / sqrt(3)
    assert incs[-1][1]["p"].mean() == pytest.approx(5.0 / math.sqrt(3), rel=2e-3)


TANGLE = """
description = "Elastic block compressed to 10 % of its height in one increment"
[geometry]
builder = "rectangle"
x = [0.0, 1.0]           # m
y = [0.0, 1.0]           # m
h = 0.5                  # m
[material]
E = 70e9                 # Pa
nu = 0.3                 # 1
[kinematics]
kind = "updated-lagrangian"
min_area_ratio = 0.5     # 1
[boundary.left]
ux = 0.0                 # m
[boundary.bottom]
uy = 0.0                 # m
[boundary.top]
uy = -0.9                # m at load factor 1
[loading]
steps = 1
[output]
png = false
"""


def test_an_increment_that_would_tangle_the_mesh_is_cut(scene_file, tmp_path, quiet):
    """One increment to 10 % height with kinematics.min_area_ratio = 0.5: refused as "mesh would invert",
    the step is cut until every increment keeps half of each cell's area."""
    lines: list[str] = []
    root = run(scene_file(TANGLE, "tangle.toml"), out=tmp_path / "t", progress=lines.append, png=False)
    assert "mesh would invert" in "\n".join(lines)
    incs = increments(root)
    assert len(incs) > 1 and incs[-1][0]["load_factor"] == pytest.approx(1.0)
    assert min(rec["ul_min_area_ratio"] for rec, _, _ in incs) > 0.5
    assert np.abs(incs[-1][1]["strain_yy"] / math.log(0.1) - 1).max() < 1e-9     # Newton tolerance


@pytest.mark.parametrize("change, words", [
    ('[kinematics]\nkind = "updated-lagrangian"\n[thermal]\nk = 50.0\nrho = 7800.0\nc = 460.0\nalpha = 1.2e-5\nduration = 1.0\ncoupling = "staggered"\n'
     '[thermal.moving_source]\npower = 100.0\nradius = 0.1\nstart = [0.0, 0.0]\nvelocity = [1.0, 0.0]\n',
     "not implemented with a moving heat source"),
    ('[kinematics]\nkind = "large"\n', "valid: small-strain, updated-lagrangian"),
    ('[kinematics]\ninitial_strain = [1e-3, 0.0, 0.0]\n', "needs kinematics.kind"),
    ("ROTATE", "no ux/uy/uz beside them"),
])
def test_bad_kinematics_tables_are_refused_by_the_scene_check(scene_file, change, words):
    """`wendel check` exits 2 with the file and the key (no traceback)."""
    import subprocess
    import sys

    base = (WORKFLOWS / "smoke.toml").read_text()
    text = base.replace("[boundary.top]\n", "[boundary.top]\nrotation = 1.0\n") if change == "ROTATE" \
        else base + "\n" + change
    path = scene_file(text)
    out = subprocess.run([sys.executable, "-m", "wendel.cli", "check", str(path)], capture_output=True, text=True)
    assert out.returncode == 2, out.stdout + out.stderr
    assert words in out.stdout + out.stderr and "Traceback" not in out.stderr
