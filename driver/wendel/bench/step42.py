"""Benchmarks of deal.II step-42 in 3D (``wendel bench step42``, ``wendel bench step42-dealii``).

``step42`` runs workflows/ball-indent.toml over a sequence of graded gmsh meshes (element size h away from
the contact, h/8 in the contact zone) and workflows/stamp-indent.toml once, each FreeFEM launch in its own
process so that its peak memory is measured; rows give DoFs, Newton and linear iterations, the step-42
fingerprints, wall time by phase (assembly, constitutive update, linear solve, active-set update, output)
and peak memory per DoF. Then the strong-scaling pair (ffddm on 1 and 2 ranks) at one size. It writes
``step42_force_vs_time.png``: contact force against wall time, next to deal.II's figures. Last, when deal.II's
step-42 is installed (``make dealii``), deal.II and wendel's default path run interleaved in the same bench run
(the rows of ``step42-pair``: per Newton step per DoF and whole-run wall times with their ratios).

``step42-dealii`` builds and runs deal.II's own step-42 (Debian's ``libdeal.ii-dev`` and ``libdeal.ii-doc``,
``apt-get install libdeal.ii-dev libdeal.ii-doc cmake``) on this machine: Q1, one MPI rank, global
refinements 4 and 5 and the adaptive cycles (ball), and the stamp with its own image and with ours. It is
never part of ``make test``.
"""

from __future__ import annotations

import json
import os
import re
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path

from . import WORKFLOWS, register

DEALII_EXAMPLE = Path("/usr/share/doc/libdeal.ii-doc/examples/step-42")

from ..results.comparisons import DEALII_REFERENCE, FINE_FORCE


def _run_measured(scene: Path, out: Path, h: float | None = None, solver: str | None = None,
                  ranks: int = 1, smoke: bool = False) -> dict:
    """Run a scene in a child Python process; return its summary with the peak memory of the FreeFEM ranks."""
    code = ("import json, resource, sys\n"
            "from wendel.scene import load\n"
            "from wendel.loop import run_scene\n"
            "scene_path, out, h, solver, ranks, smoke = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], "
            "int(sys.argv[5]), sys.argv[6] == '1'\n"
            "scene = load(scene_path, smoke=smoke)\n"
            "if h != '-': scene.geometry.h = float(h)\n"
            "if solver != '-': scene.numerics.solver = solver\n"
            "scene.numerics.assembly = 'freefem'\n"     # the FreeFEM-language path this bench has always measured
            "scene.numerics.ranks = ranks\n"
            "scene.output.png = False\n"
            "run_scene(scene, scene_path, out, progress=lambda *_: None)\n"
            "print('MAXRSS_KB', resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)\n")
    shutil.rmtree(out, ignore_errors=True)
    proc = subprocess.run([sys.executable, "-c", code, str(scene), str(out), "-" if h is None else repr(h),
                           solver or "-", str(ranks), "1" if smoke else "0"],
                          capture_output=True, text=True, check=True)
    rss = int(re.findall(r"MAXRSS_KB (\d+)", proc.stdout)[-1]) * 1024
    s = json.loads((out / "summary.json").read_text())
    s["peak_memory_bytes"] = rss
    return s


def _row(case: str, s: dict) -> dict:
    last, ph = s["last_increment"], s["wall_time_by_phase"]
    active_set = last.get("time_active_set", 0.0)
    newton = s["newton_iterations"]
    inner = ph["assembly"] + ph["constitutive"] + ph["linear_solve"]
    return {"case": case, "solver": last["solver"], "ranks": last["ranks"], "dofs": s["dofs"],
            "newton_iterations": newton, "linear_iterations": last["linear_iterations"],
            "contact_force": last["contact_force"], "contact_active_nodes": last["contact_active_nodes"],
            "contact_max_pressure": last["contact_max_pressure"], "plastic_volume": last["plastic_volume"],
            "wall_time": s["wall_time"], "mesh": ph["mesh"], "assembly": ph["assembly"] - active_set,
            "constitutive": ph["constitutive"], "linear_solve": ph["linear_solve"], "active_set": active_set,
            "output": ph["freefem_output"] + ph["driver_output"], "startup": ph["freefem_startup"],
            "seconds_per_newton_step": inner / max(newton, 1),
            "us_per_newton_step_per_dof": 1e6 * inner / max(newton, 1) / s["dofs"],
            "peak_memory_per_dof_kb": s["peak_memory_bytes"] / s["dofs"] / 1024}


@register("step42")
def step42(quick: bool, workdir: Path) -> list[dict]:
    """Ball over graded meshes (direct and CG), the stamp, ffddm on 1 and 2 ranks; force-vs-time plot; then deal.II
    and wendel's default path interleaved (step42-pair's rows) when deal.II is installed."""
    ball, stamp = WORKFLOWS / "ball-indent.toml", WORKFLOWS / "stamp-indent.toml"
    sizes = [0.2, 0.1] if quick else [0.2, 0.1, 0.07, 0.05, 0.04]
    rows = []
    for h in sizes:
        # UMFPACK64 at h = 0.05 (119k DoFs) had not finished 9 factorizations after 18 min here: CG only from there
        for solver in (("direct", "cg") if h >= 0.07 else ("cg",)):
            rows.append(_row(f"ball h={h:g}", _run_measured(ball, workdir / f"ball-h{h:g}-{solver}", h=h, solver=solver)))
    rows.append(_row("stamp h=0.1", _run_measured(stamp, workdir / "stamp-h0.1", solver="cg")))
    h_par = 0.2 if quick else 0.1
    for ranks in (1, 2):
        rows.append(_row(f"ball h={h_par:g}", _run_measured(ball, workdir / f"ball-h{h_par:g}-ffddm-np{ranks}",
                                                             h=h_par, solver="ffddm", ranks=ranks)))
    plot_force_vs_time(workdir.parent.parent / "step42_force_vs_time.png", rows)
    # deal.II's step-42 and wendel's default path (PETSc-ML, compiled kernels), interleaved, with their ratios per
    # Newton step per DoF and of the whole run: the rows of `wendel bench step42-pair`, when deal.II is installed
    # (`make dealii`); otherwise a row that says how to get them
    if (DEALII_EXAMPLE / "step-42.cc").is_file():
        from .step42_pair import step42_pair

        pair = workdir.parent / "step42-pair"        # the same folder (and deal.II build) as `wendel bench step42-pair`
        rows += [{"case": "pair: " + r.pop("code"), **r} for r in step42_pair(quick, pair)]
    else:
        rows.append({"case": "pair with deal.II: not run (`make dealii` installs deal.II's step-42)"})
    return rows


def plot_force_vs_time(png: Path, rows: list[dict], dealii: list[tuple] | None = None) -> None:
    """Contact force of the ball against wall time: wendel's mesh sequence next to deal.II's figures."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    dealii = dealii or DEALII_REFERENCE
    fig, ax = plt.subplots(figsize=(6.8, 4.8))
    for solver, marker in (("direct", "o-"), ("cg", "s-")):
        pts = sorted((r["wall_time"], r["contact_force"], r["dofs"]) for r in rows
                     if r["case"].startswith("ball") and r["solver"] == solver and r["ranks"] == 1)
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], marker, label=f"wendel P1, graded gmsh mesh ({solver})")
            for t, f, n in pts:
                ax.annotate(f"{n:,}", (t, f), fontsize=7, xytext=(4, 4), textcoords="offset points")
    for kind, style in (("global", "k^--"), ("adaptive", "kv:")):
        pts = [d for d in dealii if d[0].startswith(kind)]
        ax.plot([d[5] for d in pts], [d[4] for d in pts], style, label=f"deal.II step-42 Q1, {kind} (9.4.1, 1 rank)")
    for d in dealii:
        ax.annotate(f"{d[1]:,}", (d[5], d[4]), fontsize=7, xytext=(4, -10), textcoords="offset points")
    ax.axhspan(FINE_FORCE * 0.98, FINE_FORCE * 1.02, color="green", alpha=0.12, label="within 2% of ~55 (fine mesh)")
    ax.set_xscale("log")
    ax.set_xlabel("wall time [s] (labels: DoFs)")
    ax.set_ylabel("contact force")
    ax.set_title("step-42, ball: contact force against run time")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png, dpi=120)
    plt.close(fig)


# ---------------------------------------------------------------- deal.II's step-42 on this machine

def _dealii_build(workdir: Path) -> Path:
    """Configure and build step-42 from libdeal.ii-doc in release mode; return the executable."""
    if not (DEALII_EXAMPLE / "step-42.cc").is_file():
        raise RuntimeError("deal.II's step-42 is not installed: `make dealii` (apt-get install libdeal.ii-dev libdeal.ii-doc cmake)")
    src = workdir / "src"
    exe = src / "step-42"
    if exe.is_file():
        return exe
    shutil.rmtree(src, ignore_errors=True)
    shutil.copytree(DEALII_EXAMPLE, src)
    subprocess.run(["cmake", "-DCMAKE_BUILD_TYPE=Release", "."], cwd=src, check=True, capture_output=True)
    subprocess.run(["make", "release"], cwd=src, check=True, capture_output=True)
    subprocess.run(["make", "-j2"], cwd=src, check=True, capture_output=True)
    return exe


def _pbm_from_pgm(pgm: Path, pbm: Path) -> None:
    """Our stamp image as step-42's obstacle.pbm (1 = raised, first row at y = 1)."""
    tokens = [t for line in pgm.read_text().splitlines() if not line.startswith("#") for t in line.split()]
    nx, ny, vmax = int(tokens[1]), int(tokens[2]), float(tokens[3])
    vals = ["1" if float(v) > vmax / 2 else "0" for v in tokens[4:4 + nx * ny]]
    pbm.write_text(f"P1\n{nx} {ny}\n" + "\n".join(" ".join(vals[j * nx:(j + 1) * nx]) for j in range(ny)) + "\n")


def _dealii_run(exe: Path, folder: Path, refinements: int, cycles: int, strategy: str, obstacle: str,
                image: Path | None = None) -> list[dict]:
    """One step-42 run; one row per cycle (DoFs, Newton steps, contact nodes, force, cumulative wall time)."""
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    shutil.copyfile(image or DEALII_EXAMPLE / "obstacle.pbm", folder / "obstacle.pbm")
    (folder / "run.prm").write_text(
        f"set polynomial degree = 1\nset number of initial refinements = {refinements}\n"
        f"set number of cycles = {cycles}\nset refinement strategy = {strategy}\nset obstacle = {obstacle}\n"
        f"set output directory = out\nset transfer solution = false\nset base mesh = box\n")
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1", OMP_NUM_THREADS="1",
               OPENBLAS_NUM_THREADS="1")
    t0 = time.perf_counter()
    stamps: list[float] = []
    lines: list[str] = []
    with subprocess.Popen([str(exe), "run.prm"], cwd=folder, env=env, stdout=subprocess.PIPE, text=True) as p:
        for line in p.stdout:
            lines.append(line)
            if line.startswith("Contact force"):
                stamps.append(time.perf_counter() - t0)
    (folder / "stdout.txt").write_text("".join(lines))
    if p.returncode:
        raise RuntimeError(f"step-42 failed in {folder} (exit code {p.returncode})")
    rows, cur = [], {}
    for line in lines:
        if m := re.match(r"Cycle (\d+):", line):
            cur = {"cycle": int(m.group(1)), "newton_iterations": 0}
        elif m := re.search(r"Number of degrees of freedom: (\d+)", line):
            cur["dofs"] = int(m.group(1))
        elif re.search(r"Newton iteration \d+", line):
            cur["newton_iterations"] += 1
        elif m := re.search(r"Size of active set: (\d+)", line):
            cur["contact_active_nodes"] = int(m.group(1))
        elif m := re.match(r"Contact force = ([-0-9.eE+]+)", line):
            cur["contact_force"] = float(m.group(1))
            cur["wall_time_cumulative"] = stamps[len(rows)]
            rows.append(cur)
    return rows


@register("step42-dealii")
def step42_dealii(quick: bool, workdir: Path) -> list[dict]:
    """deal.II's step-42 (Q1, 1 rank): ball, global 4 and 5 refinements and adaptive cycles; stamps."""
    exe = _dealii_build(workdir)
    rows = []
    cases = [("ball global", 4, 1, "global", "sphere", None), ("stamp global (its image)", 4, 1, "global", "read from file", None)]
    if not quick:
        cases += [("ball global", 5, 1, "global", "sphere", None), ("ball adaptive", 3, 5, "percentage", "sphere", None)]
    pbm = workdir / "stamp-character.pbm"
    _pbm_from_pgm(WORKFLOWS / "images" / "stamp-character.pgm", pbm)
    cases.append(("stamp global (our image)", 4, 1, "global", "read from file", pbm))
    for name, ref, cycles, strategy, obstacle, image in cases:
        tag = re.sub(r"[^a-z0-9]+", "-", f"{name}-{ref}")
        for r in _dealii_run(exe, workdir / tag, ref, cycles, strategy, obstacle, image):
            rows.append({"case": f"{name}, {ref} initial refinements, cycle {r['cycle']}", **r})
    return rows
