"""Von Mises plasticity (edp/lib/plasticity.idp): uniaxial closed forms of the three laws, Newton order,
step cutting, Hill's thick-walled cylinder (plastic radius, limit load)."""

from __future__ import annotations

import itertools
import json
import math
import subprocess
from pathlib import Path

import numpy as np
import pytest

from wendel import freefem
from wendel.results import vtu as output
from wendel.loop import StepCutError, run

from conftest import ROOT, WORKFLOWS

E, NU, SIGMA0 = 70e9, 0.3, 250e6
LABEL = {"left": 1, "right": 2, "bottom": 3, "top": 4, "front": 5, "back": 6}


def cube_msh(path: Path, n: int = 1) -> Path:
    """Unit cube of n^3 Kuhn cubes (6 tetrahedra each), MSH 2.2, faces labelled as in meshes/labels.py."""
    idx = lambda i, j, k: i + (n + 1) * (j + (n + 1) * k)  # noqa: E731
    g = np.linspace(0.0, 1.0, n + 1)
    pts = np.array([[g[i], g[j], g[k]] for k in range(n + 1) for j in range(n + 1) for i in range(n + 1)])
    tets = []
    for i, j, k in itertools.product(range(n), repeat=3):
        for perm in itertools.permutations(range(3)):
            c = [i, j, k]
            t = [idx(*c)]
            for ax in perm:
                c[ax] += 1
                t.append(idx(*c))
            if np.linalg.det(pts[t[1:]] - pts[t[0]]) < 0:
                t = [t[0], t[2], t[1], t[3]]
            tets.append(t)
    faces: dict[tuple, int] = {}
    for t in tets:
        for f in itertools.combinations(t, 3):
            faces[tuple(sorted(f))] = faces.get(tuple(sorted(f)), 0) + 1
    tris = []
    for key, count in faces.items():
        if count != 1:
            continue
        x = pts[list(key)]
        for ax, (lo, hi) in enumerate([("left", "right"), ("front", "back"), ("bottom", "top")]):
            if np.ptp(x[:, ax]) < 1e-12:
                tris.append((LABEL[lo if x[0, ax] < 0.5 else hi], key))
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$Nodes", str(len(pts))]
    lines += [f"{a + 1} {p[0]:.17g} {p[1]:.17g} {p[2]:.17g}" for a, p in enumerate(pts)]
    lines += ["$EndNodes", "$Elements", str(len(tris) + len(tets))]
    e = 0
    for lab, t in tris:
        e += 1
        lines.append(f"{e} 2 2 {lab} {lab} " + " ".join(str(v + 1) for v in t))
    for t in tets:
        e += 1
        lines.append(f"{e} 4 2 100 100 " + " ".join(str(v + 1) for v in t))
    lines.append("$EndElements")
    path.write_text("\n".join(lines) + "\n")
    return path


def solve(tmp: Path, macros: list[str], mesh: Path, loads, bc, trac=None, **opts) -> Path:
    """One FreeFEM launch of edp/mechanics.edp with the -D ``macros``; returns the output folder (exit code 4 is
    allowed)."""
    out = tmp / "out"
    out.mkdir(parents=True, exist_ok=True)
    (tmp / "loads.txt").write_text(f"{len(loads)}\n" + "".join(f"{f!r}\n" for f in loads))
    (tmp / "bc.txt").write_text(f"{len(bc)}\n" + "".join(f"{r}\n" for r in bc))
    args = ["mpirun", "-np", "1", "FreeFem++-mpi", "-nw", "-v", "0", str(ROOT / "edp" / "mechanics.edp"), *macros, "-out", str(out),
            "-mesh", str(mesh), "-loads", str(tmp / "loads.txt"), "-bc", str(tmp / "bc.txt"),
            "-mat_E", repr(E), "-mat_nu", repr(NU)]
    if trac:
        (tmp / "trac.txt").write_text(f"{len(trac)}\n" + "".join(f"{r}\n" for r in trac))
        args += ["-trac", str(tmp / "trac.txt")]
    for k, v in opts.items():
        args += [f"-{k}", str(v)]
    p = subprocess.run(args, env=freefem.environment(), capture_output=True, text=True, timeout=120)
    assert p.returncode in (0, 4), (out / "error.txt").read_text() if (out / "error.txt").exists() else p.stdout[-2000:]
    return out


def records(out: Path) -> list[dict]:
    return [json.loads((d / "record.json").read_text()) for d in sorted(out.glob("inc-*")) if (d / "done").exists()]


def cell(out: Path, inc: int, name: str) -> np.ndarray:
    return output.read_array(out / f"inc-{inc:04d}" / f"{name}.cell.txt")


# ---- uniaxial stress: unit cube, x, y, z symmetry planes, top pulled by DELTA * load factor
DELTA = 0.01
UNIAXIAL_BC = ["1 0 0", "5 1 0", "3 2 0", f"4 2 {DELTA!r}"]
LOADS = [0.1, 0.2, 0.3, 0.4, 0.5, 0.7, 1.0]
JC = dict(A=250e6, B=400e6, n=0.3, C=0.02, rate0=1.0, m=1.1, Tr=293.15, Tm=1700.0)


def jc_yield(p, dp, dt, T):
    rate = dp / dt if dt > 0 else 0.0
    ts = min(max((T - JC["Tr"]) / (JC["Tm"] - JC["Tr"]), 0.0), 1.0)
    return (JC["A"] + JC["B"] * p ** JC["n"]) * (1 + JC["C"] * math.log(max(rate, JC["rate0"]) / JC["rate0"])) \
        * (1 - ts ** JC["m"])


def uniaxial_reference(law: str, strains, load_time=0.0, T=293.15, H=1e9):
    """Closed-form uniaxial stress, backward Euler in time: per increment sigma = E (eps - p), sigma = sigma_y."""
    out, p, lf_old = [], 0.0, 0.0
    for lf, eps in strains:
        if law == "perfect":
            sig = min(E * eps, SIGMA0)
        elif law == "linear":
            sig = E * eps if E * eps <= SIGMA0 else SIGMA0 + E * H / (E + H) * (eps - SIGMA0 / E)
        else:
            dt = (lf - lf_old) * load_time
            g = lambda q: E * (eps - q) - jc_yield(q, q - p, dt, T)  # noqa: E731
            if g(p) <= 0:
                sig = E * (eps - p)
            else:
                lo, hi = p, eps
                for _ in range(200):
                    mid = 0.5 * (lo + hi)
                    lo, hi = (mid, hi) if g(mid) > 0 else (lo, mid)
                p = 0.5 * (lo + hi)
                sig = E * (eps - p)
        out.append((sig, p))
        lf_old = lf
    return [s for s, _ in out]


@pytest.fixture(scope="module")
def cube(tmp_path_factory):
    return cube_msh(tmp_path_factory.mktemp("cube") / "cube.msh")


@pytest.mark.parametrize("law, opts", [
    ("perfect", {"plast_law": 0, "plast_sigma0": SIGMA0}),
    ("linear", {"plast_law": 1, "plast_sigma0": SIGMA0, "plast_H": 1e9}),
    ("jc-quasistatic", {"plast_law": 2, "plast_jc_A": JC["A"], "plast_jc_B": JC["B"], "plast_jc_n": JC["n"]}),
    ("jc-fast-hot", {"plast_law": 2, "plast_jc_A": JC["A"], "plast_jc_B": JC["B"], "plast_jc_n": JC["n"],
                     "plast_jc_C": JC["C"], "plast_jc_rate0": JC["rate0"], "plast_jc_m": JC["m"],
                     "plast_jc_Tr": JC["Tr"], "plast_jc_Tm": JC["Tm"], "plast_T": 700.0, "plast_load_time": 1e-3}),
])
def test_uniaxial_curve_matches_closed_form(tmp_path, cube, law, opts):
    out = solve(tmp_path, ["-Ddimension=3", "-DWITHPLASTICITY=1"], cube, LOADS, UNIAXIAL_BC, **opts)
    recs = records(out)
    assert len(recs) == len(LOADS)
    strains = [(lf, lf * DELTA) for lf in LOADS]
    if law.startswith("jc"):
        ref = uniaxial_reference("jc", strains, load_time=opts.get("plast_load_time", 0.0), T=opts.get("plast_T", JC["Tr"]))
    else:
        ref = uniaxial_reference(law, strains)
    for k, (r, s_ref) in enumerate(zip(recs, ref)):
        vm = cell(out, k + 1, "vonMises")
        assert np.all(np.abs(vm - s_ref) <= 1e-6 * s_ref), (law, k, vm.max(), s_ref)
        # the plastic strain closes the curve: eps = sigma / E + p
        p = cell(out, k + 1, "p")
        assert np.all(np.abs(p + vm / E - strains[k][1]) <= 1e-6 * strains[k][1])
    if law == "jc-fast-hot":       # the rate and temperature terms act: not the quasi-static curve
        qs = uniaxial_reference("jc", strains)
        assert abs(ref[-1] - qs[-1]) > 0.05 * qs[-1]



@pytest.mark.parametrize("scene, law", [("uniaxial-linear", "linear"), ("uniaxial-jc", "jc")])
def test_uniaxial_scene_matches_closed_form(tmp_path, quiet, scene, law):
    """The uniaxial scenes (box builder with named faces) through the driver: the same 1e-6 closed form."""
    root = run(WORKFLOWS / f"{scene}.toml", smoke=True, out=tmp_path / "run", png=False, progress=quiet)
    fem = root / "fem"
    recs = records(fem)
    assert len(recs) == len(LOADS)
    strains = [(lf, lf * DELTA) for lf in LOADS]
    ref = uniaxial_reference(law, strains)
    for k, s_ref in enumerate(ref):
        vm = cell(fem, k + 1, "vonMises")
        assert np.all(np.abs(vm - s_ref) <= 1e-6 * s_ref), (scene, k, vm.max(), s_ref)
        p = cell(fem, k + 1, "p")
        assert np.all(np.abs(p + vm / E - strains[k][1]) <= 1e-6 * strains[k][1])

# ---- Hill's cylinder (plane strain, quarter ring)
RI, RE = 1.0, 1.3
Q_LIM = 2 / math.sqrt(3) * SIGMA0 * math.log(RE / RI)       # 75.74 MPa
CYL_BC = ["11 0 0", "12 1 0"]


def hill_pressure(c: float) -> float:
    """Internal pressure at which the plastic zone reaches radius c (Hill, plane strain)."""
    return 2 / math.sqrt(3) * SIGMA0 * (math.log(c / RI) + (RE ** 2 - c ** 2) / (2 * RE ** 2))


def hill_radius(q: float) -> float:
    lo, hi = RI, RE
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if hill_pressure(mid) < q else (lo, mid)
    return 0.5 * (lo + hi)


def ring(tmp: Path, h: float) -> Path:
    import meshes

    return meshes.build("ring", tmp / "ring.msh", r_inner=RI, r_outer=RE, h=h).path


def test_newton_converges_quadratically_with_linear_hardening(tmp_path):
    out = solve(tmp_path, ["-Ddimension=2", "-DWITHPLASTICITY=1"], ring(tmp_path, 0.05), [0.7], CYL_BC,
                trac=["7 0 0 0 100e6"], plast_law=1, plast_sigma0=SIGMA0, plast_H=5e9, newton_tol=1e-12)
    rows = np.genfromtxt(out / "inc-0001" / "newton.csv", delimiter=",", names=True)
    r = rows["relative_residual"]
    assert records(out)[0]["plastic_points"] > 0
    # near the solution each residual is about the square of the previous one: log ratio near 2
    tail = [(r[k], r[k + 1]) for k in range(1, len(r) - 1) if 1e-14 < r[k + 1] and r[k] < 1e-2]
    assert tail, r
    assert all(math.log(b) / math.log(a) > 1.6 for a, b in tail), r


CYL_SCENE = (WORKFLOWS / "cylinder.toml").read_text()


def scene_with(text: str, **tables) -> str:
    """Replace whole tables of a scene text (a table ends at the next blank line)."""
    for name, body in tables.items():
        start = text.index(f"[{name}]")
        end = text.find("\n\n", start)
        text = text[:start] + f"[{name}]\n{body}" + (text[end:] if end >= 0 else "\n")
    return text


def test_step_cutting_recovers_from_a_too_large_increment(scene_file, tmp_path, quiet):
    text = scene_with(CYL_SCENE, loading="factors = [0.74]\nmax_cuts = 4",
                      numerics="newton_maxit = 5",
                      plasticity='law = "linear"\nsigma0 = 250e6\nH = 5e9')
    text = text.replace("h = 0.02 ", "h = 0.05 ")
    text = text.replace("nu = 0.49 ", "nu = 0.3 ")     # (at 0.49 this increment converges in 5 iterations)
    root = run(scene_file(text), out=tmp_path / "run", png=False, progress=quiet)
    state = json.loads((root / "checkpoint.json").read_text())
    assert state["cuts"] >= 1
    assert state["accepted"][-1][1] == pytest.approx(0.74)
    assert (root / "failed-attempts").is_dir()


def test_cylinder_plastic_radius_and_limit_load(scene_file, tmp_path, quiet):
    text = scene_with(CYL_SCENE, loading="factors = [0.6, 0.7, 0.74, 0.755, 0.76]\nmax_cuts = 2")
    with pytest.raises(StepCutError, match="limit load reached"):
        run(scene_file(text), out=tmp_path / "run", png=False, progress=quiet)
    fem = tmp_path / "run" / "fem"
    recs = records(fem)
    failed = json.loads((fem / "failed.json").read_text())
    # the limit pressure lies between the last accepted and the failed load (2 %)
    q_ok, q_fail = recs[-1]["load_factor"] * 100e6, failed["load_factor"] * 100e6
    assert q_ok <= Q_LIM * 1.02 and q_fail >= Q_LIM * 0.98, (q_ok, q_fail, Q_LIM)
    assert failed["stiffness_ratio"] < 1e-3
    # plastic radius from the plastic area of the quarter, pi/4 (c^2 - Ri^2), against Hill below the limit
    for r in recs:
        q = r["load_factor"] * 100e6
        if q > hill_pressure(RI) and q < 0.95 * Q_LIM:
            c = math.sqrt(RI ** 2 + 4 * r["plastic_volume"] / math.pi)
            assert abs(c - hill_radius(q)) <= 0.02 * hill_radius(q), (q, c, hill_radius(q))
            assert abs(hill_pressure(c) - q) <= 0.02 * q


def test_cylinder_scene_records_the_plastic_radius_error(tmp_path, quiet):
    root = run(WORKFLOWS / "cylinder.toml", smoke=True, out=tmp_path / "run", png=False, progress=quiet)
    recs = records(root / "fem")
    assert recs[0]["error_plastic_radius"] == -1                  # 50 MPa: still elastic
    for r in recs[1:]:
        q = r["load_factor"] * 100e6
        assert r["hill_plastic_radius"] == pytest.approx(hill_radius(q), rel=1e-9)
        assert abs(r["plastic_radius"] - hill_radius(q)) <= 0.04 * hill_radius(q)   # h = 0.05: up to 2.9 %
    assert 0 < recs[-1]["error_plastic_radius"] < 0.3             # depth of the zone, h = 0.05 (measured 0.207)
    s = json.loads((root / "summary.json").read_text())
    assert "error_plastic_radius" in json.dumps(s)
    # the cylinder bench's per-increment costs: differences of the cumulative record times add up
    from wendel.bench import BENCHES
    from wendel.bench.cylinder import increment_costs

    assert "cylinder" in BENCHES
    costs = increment_costs(root / "fem")
    assert [c["newton_iterations"] for c in costs] == [r["newton_iterations"] for r in recs]
    assert all(c["total"] > 0 and c["assembly"] >= 0 and c["solve"] >= 0 for c in costs)
    assert sum(c["total"] for c in costs) == pytest.approx(recs[-1]["time_total"], rel=1e-9)   # one launch


def test_hill_reference_needs_the_perfect_law(scene_file, tmp_path, quiet):
    text = CYL_SCENE.replace('law = "perfect"', 'law = "linear"\nH = 1e9')
    with pytest.raises(Exception, match="hill"):
        run(scene_file(text), smoke=True, out=tmp_path / "run", png=False, progress=quiet)
