"""Compiled element kernels (numerics.assembly = "compiled": edp/plugins/wendel_kernels.cpp through lib/kernels.idp)
against the FreeFEM-language forms on step-42's ball (contact + J2 plasticity, 3D P1): the same Newton and
Krylov iterations, active set and fields to round-off; scenes the kernels do not cover are refused."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from wendel.results.vtu import read_array

from conftest import WORKFLOWS, smoke_ball


def ball(out, assembly: str, solver: str = "cg", ranks: int = 1) -> tuple[dict, np.ndarray]:
    root = smoke_ball(out, solver=solver, ranks=ranks, assembly=assembly)
    u = read_array(sorted(root.glob("fem/inc-*/u.node.txt"))[-1])
    summary = json.loads((root / "summary.json").read_text())
    summary["root"] = root
    return summary, u


@pytest.fixture(scope="module")
def ball_freefem(tmp_path_factory):
    return ball(tmp_path_factory.mktemp("freefem"), "freefem")


def test_compiled_kernels_reproduce_the_varf_assembly(tmp_path, ball_freefem):
    (f, uf), (c, uc) = ball_freefem, ball(tmp_path / "compiled", "compiled")
    assert f["completed"] and c["completed"]
    lf, lc = f["last_increment"], c["last_increment"]
    assert lf["plastic_points"] > 0 and lf["contact_active_nodes"] > 0      # the kernels' whole tangent is used
    assert c["newton_iterations"] == f["newton_iterations"]
    assert lc["linear_iterations"] == lf["linear_iterations"]
    assert lc["contact_active_nodes"] == lf["contact_active_nodes"]
    assert lc["plastic_points"] == lf["plastic_points"]
    for key in ("contact_force", "max_von_mises", "plastic_volume", "max_plastic_strain", "strain_energy"):
        assert lc[key] == pytest.approx(lf[key], rel=1e-10), key
    assert np.abs(uc - uf).max() <= 1e-10 * np.abs(uf).max()
    # the cell fields the kernels take from the quadrature state, not from P0 interpolations (kernelCellStress)
    for name in ("vonMises", "strain_xx", "strain_zz", "strain_yz", "strain_xy"):
        a, b = (read_array(sorted((r / "fem").glob("inc-*"))[-1] / f"{name}.cell.txt")
                for r in (f["root"], c["root"]))
        assert a.shape == b.shape and np.abs(b - a).max() <= 1e-9 * np.abs(a).max(), name
    # the point of the kernels: the assembly of the Newton step is cheaper than FreeFEM's forms
    assert lc["time_tangent"] < lf["time_tangent"]


def test_compiled_kernels_on_two_petsc_ranks(tmp_path, ball_freefem):
    """Rank-local assembly: each of 2 PETSc ranks assembles its own slab of tetrahedra and the plugin adds the
    parts; the iterates, force, active set and KKT residuals of 1 PETSc rank and of the varf forms."""
    (f, uf) = ball_freefem
    (p, up), (c, uc) = (ball(tmp_path / f"np{r}", "compiled", solver="petsc", ranks=r) for r in (1, 2))
    lp, lc = p["last_increment"], c["last_increment"]
    assert lc["ranks"] == 2 and lp["ranks"] == 1
    assert 0 < lc["petsc_local_tets"] < 0.75 * lc["elements"] and lp["petsc_local_tets"] == 0
    assert c["newton_iterations"] == p["newton_iterations"] == f["newton_iterations"]
    assert lc["contact_active_nodes"] == lp["contact_active_nodes"] == f["last_increment"]["contact_active_nodes"]
    assert lc["plastic_points"] == lp["plastic_points"]
    for key in ("contact_force", "max_von_mises", "plastic_volume"):
        assert lc[key] == pytest.approx(lp[key], rel=1e-7), key
    assert lc["contact_force"] == pytest.approx(f["last_increment"]["contact_force"], rel=1e-7)
    assert lc["kkt_max_complementarity"] <= 1e-8 and lc["kkt_max_penetration"] <= 1e-8
    assert np.abs(uc - up).max() <= 1e-7 * np.abs(up).max()
    assert np.abs(uc - uf).max() <= 1e-7 * np.abs(uf).max()


def test_rank_local_constitutive_state_on_two_petsc_ranks(tmp_path):
    """Each of 2 PETSc ranks updates the quadrature points of its own tetrahedra only (kernels.idp, kernelPoints)
    and gathers the state where it is needed whole (kernelGather): over 3 increments of a moving ball, each
    starting from the gathered state of the last, every written field and checkpoint array (plastic strain,
    p, yield stress at the quadrature points, cell stress and strain) of 1 PETSc rank, and its records."""
    from wendel.loop import run_scene
    from wendel.scene import load

    path = WORKFLOWS / "ball-indent.toml"
    runs = []
    for ranks in (1, 2):
        scene = load(path, smoke=True)
        scene.numerics.solver, scene.numerics.ranks, scene.numerics.assembly = "petsc", ranks, "compiled"
        scene.loading.steps = 3
        scene.contact.center, scene.contact.displacement = [0.5, 0.5, 1.6], -0.02   # in contact from increment 2
        scene.output.png = scene.output.vtu = False
        runs.append(run_scene(scene, path, tmp_path / f"np{ranks}", smoke=True, progress=lambda *_: None) / "fem")
    one, two = runs
    incs = sorted(d.name for d in one.glob("inc-*"))
    assert incs == sorted(d.name for d in two.glob("inc-*")) and len(incs) == 3
    plastic = []
    for inc in incs:
        r1, r2 = (json.loads((f / inc / "record.json").read_text()) for f in runs)
        assert r2["ranks"] == 2 and r2["newton_iterations"] == r1["newton_iterations"]
        assert r2["plastic_points"] == r1["plastic_points"]
        for key in ("contact_force", "max_von_mises", "plastic_volume", "max_plastic_strain", "strain_energy"):
            assert r2[key] == pytest.approx(r1[key], rel=1e-9, abs=1e-300), (inc, key)
        plastic.append(r1["plastic_points"])
        names = sorted(f.name for f in (one / inc).glob("*.txt") if f.name != "newton.csv")
        assert {"plast_epsp.qp.txt", "plast_p.qp.txt", "plast_sigma_y.qp.txt", "vonMises.cell.txt",
                "strain_xy.cell.txt", "epsp_xx.cell.txt"} <= set(names)
        for name in names:
            a, b = read_array(one / inc / name), read_array(two / inc / name)
            assert a.shape == b.shape and np.abs(b - a).max() <= 1e-9 * max(np.abs(a).max(), 1e-300), (inc, name)
    assert plastic[1] > 0 and plastic[2] > plastic[1]      # the later increments start from a plastic state


def test_failed_increment_record_on_two_petsc_ranks(tmp_path):
    """A failed increment's record from the rank-local state made whole (kernelGatherTrial): the plastic points
    and the stiffness ratio of the FreeFEM-language tangent of 1 PETSc rank."""
    from wendel.loop import run_scene
    from wendel.scene import load

    path = WORKFLOWS / "ball-indent.toml"
    failed = []
    for ranks in (1, 2):
        scene = load(path, smoke=True)
        scene.numerics.solver, scene.numerics.ranks, scene.numerics.assembly = "petsc", ranks, "compiled"
        scene.numerics.newton_maxit, scene.loading.max_cuts = 2, 0         # Newton stops before it converges
        scene.output.png = scene.output.vtu = False
        with pytest.raises(Exception, match="Newton did not converge"):
            run_scene(scene, path, tmp_path / f"np{ranks}", smoke=True, progress=lambda *_: None)
        failed.append(json.loads((tmp_path / f"np{ranks}" / "fem" / "failed.json").read_text()))
    one, two = failed
    assert one["plastic_points"] == two["plastic_points"] > 0
    assert two["stiffness_ratio"] == pytest.approx(one["stiffness_ratio"], rel=1e-9)


def test_compiled_kernels_with_the_direct_solver(tmp_path):
    """The direct solver factorizes the kernels' matrix (contact lifted through K, not masked): the same iterates."""
    (f, uf), (c, uc) = (ball(tmp_path / a, a, solver="direct") for a in ("freefem", "compiled"))
    assert c["newton_iterations"] == f["newton_iterations"]
    assert c["last_increment"]["contact_force"] == pytest.approx(f["last_increment"]["contact_force"], rel=1e-10)
    assert np.abs(uc - uf).max() <= 1e-10 * np.abs(uf).max()


@pytest.mark.parametrize("scene, extra, why", [
    ("hertz-3d", "", "needs a [plasticity] table"),
    ("ul-tension-3d", "", "small-strain"),
    ("cylinder", "", "a 3D body"),
])
def test_compiled_assembly_refused_where_it_does_not_apply(tmp_path, scene, extra, why):
    text = (WORKFLOWS / f"{scene}.toml").read_text()
    text = text.replace("[numerics]", "[numerics]\nassembly = \"compiled\"", 1) if "[numerics]" in text \
        else text + "\n[numerics]\nassembly = \"compiled\"\n"
    bad = tmp_path / "bad.toml"
    bad.write_text(text + extra)
    r = subprocess.run([sys.executable, "-m", "wendel.cli", "check", str(bad)], capture_output=True, text=True)
    assert r.returncode == 2
    assert "numerics.assembly" in r.stderr and why in r.stderr and "bad.toml" in r.stderr
    assert "Traceback" not in r.stderr


PART_PROBE = """load "msh3"
load "wendel_kernels"
mesh3 Th = cube(9, 6, 5, [2 * x, y, z]);      // longest side along x
real[int] order(1);
int nt = Th.nt;
int[int] mine(3);
for (int r = 0; r < 3; ++r) mine[r] = wendelPart3(Th, r, 3, order);
cout << "nv " << Th.nv << " nt " << nt << " tets " << mine[0] << " " << mine[1] << " " << mine[2] << endl;
ofstream f("{out}");
for (int a = 0; a < Th.nv; ++a) f << Th(a).x << " " << order[3 * a] << " " << order[3 * a + 1] << " " << order[3 * a + 2] << endl;
"""


def test_partition_slabs_keep_the_mesh_numbering(tmp_path):
    """wendelPart3 on 3 ranks: one slab of equal vertex count per rank along the longest side, each rank's PETSc
    rows a contiguous block of whole vertices, within a slab the mesh's vertex numbering (the locality of one
    rank's rows, not the coordinate order), and every tetrahedron on exactly one rank."""
    from wendel import freefem
    script, out = tmp_path / "part.edp", tmp_path / "order.txt"
    script.write_text(PART_PROBE.replace("{out}", str(out)))
    p = subprocess.run(["FreeFem++-mpi", "-nw", "-v", "0", str(script)], env=freefem.environment(),
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stdout + p.stderr
    words = next(line for line in p.stdout.splitlines() if line.startswith("nv ")).split()
    nv, nt, tets = int(words[1]), int(words[3]), [int(w) for w in words[5:8]]
    assert sum(tets) == nt and min(tets) > 0
    a = np.loadtxt(out)
    x, order = a[:, 0], a[:, 1:].astype(int)
    assert (order[:, 1] == order[:, 0] + 1).all() and (order[:, 2] == order[:, 0] + 2).all()
    pos = order[:, 0] // 3
    assert sorted(pos) == list(range(nv))                  # a permutation of whole vertices
    for r in range(3):
        slab = np.flatnonzero((pos >= nv * r // 3) & (pos < nv * (r + 1) // 3))     # rank r's rows
        assert (np.diff(pos[slab]) == 1).all()          # in the mesh's numbering: vertex order = row order
        if r < 2:
            nxt = np.flatnonzero((pos >= nv * (r + 1) // 3) & (pos < nv * (r + 2) // 3))
            assert x[slab].max() <= x[nxt].min()        # slabs along x
