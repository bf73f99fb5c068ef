"""``wendel bench sweep``: what running a campaign costs beyond its runs.

Local: 40 smoke-size runs (8 with --quick) with 2 workers. Efficiency = sum of the runs' own wall times
(each ``wendel run`` process, as the sweep measured it) / (2 x the sweep's wall time, planning and table
included); a second figure uses the runs' summary.json wall time (FreeFEM, meshing, output: without the
Python start-up of each ``wendel run``). SLURM (when root and the packages are installed): a single-node
cluster is started by scripts/slurm-local.sh, 10 runs (4 with --quick) go through submitit job arrays
with parallelism 2, once a run a task and once in two tasks (``slurm.runs_per_task``, runs forked warm); overhead
per run = (2 x sweep wall time - sum of the runs' wall times) / runs, the same formula applied to the local sweep
for comparison.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from pathlib import Path

from . import environ, register

ROOT = Path(__file__).resolve().parents[3]


def _sweep_file(workdir: Path, n: int, name: str, per_task: int = 1) -> Path:
    values = ", ".join(f"{1.0 + k:.1f}" for k in range(n))
    p = workdir / f"{name}.toml"
    p.write_text(f'description = "bench: {n} smoke runs"\nscene = "{ROOT / "workflows" / "smoke.toml"}"\n'
                 f'smoke = true\noutputs = ["strain_energy"]\n[zip]\n"material.E" = [{values}]   # Pa\n'
                 f'[slurm]\ntime = 10\nmem = "1G"\nparallelism = 2\nruns_per_task = {per_task}\n')
    return p


def _figures(rep: dict, label: str, n: int, wall: float, slots: int = 2) -> dict:
    rows = rep["rows"]
    run_walls = [r["run_wall"] or 0.0 for r in rows]
    inner = [r["wall_time"] or 0.0 for r in rows]
    return {"executor": label, "runs": n, "done": sum(r["status"] == "done" for r in rows), "slots": slots,
            "sweep_wall": wall, "sum_run_wall": sum(run_walls), "sum_summary_wall": sum(inner),
            "efficiency": sum(run_walls) / (slots * wall), "efficiency_summary_wall": sum(inner) / (slots * wall),
            "overhead_per_run": (slots * wall - sum(run_walls)) / n, "mean_run_wall": sum(run_walls) / n}


@register("sweep")
def sweep_bench(quick: bool, workdir: Path) -> list[dict]:
    """40 smoke runs locally on 2 workers (efficiency), and 10 through a local SLURM (overhead per run)."""
    from ..sweep import run_sweep

    shutil.rmtree(workdir, ignore_errors=True)
    workdir.mkdir(parents=True)
    rows = []
    n = 8 if quick else 40
    sweep = _sweep_file(workdir, n, "local")
    t0 = time.perf_counter()
    rep = run_sweep(sweep, out=workdir / "local", workers=2, quiet=True, log=lambda *_: None)
    rows.append(_figures(rep, "local", n, time.perf_counter() - t0))
    t0 = time.perf_counter()
    again = run_sweep(sweep, out=workdir / "local", workers=2, quiet=True, log=lambda *_: None)
    rows[-1]["rerun_nothing_to_do_s"] = time.perf_counter() - t0
    assert again["skipped"] == n

    needed = ("slurmctld", "slurmd", "slurmdbd", "munged", "mariadbd", "sbatch")
    if os.geteuid() != 0 or any(shutil.which(b) is None for b in needed):
        rows.append({"executor": "slurm", "runs": 0, "note": "skipped: needs root and " + " ".join(needed)})
        return rows
    m = 4 if quick else 10
    cluster = workdir / "cluster"
    script = ROOT / "scripts" / "slurm-local.sh"
    t0 = time.perf_counter()
    subprocess.run(["bash", str(script), "start", str(cluster)], check=True, capture_output=True, timeout=180)
    start_s = time.perf_counter() - t0
    try:
        with environ(SLURM_CONF=str(cluster / "etc" / "slurm.conf")):
            sweep = _sweep_file(workdir, m, "slurm")
            t0 = time.perf_counter()
            rep = run_sweep(sweep, out=workdir / "slurm", executor="slurm", quiet=True, log=lambda *_: None)
            rows.append({**_figures(rep, "slurm", m, time.perf_counter() - t0), "cluster_start_s": start_s})
            sweep = _sweep_file(workdir, m, "slurm-per-task", per_task=m // 2)
            t0 = time.perf_counter()
            rep = run_sweep(sweep, out=workdir / "slurm-per-task", executor="slurm", quiet=True, log=lambda *_: None)
            rows.append(_figures(rep, f"slurm, {m // 2} runs a task (warm)", m, time.perf_counter() - t0))
            local = _sweep_file(workdir, m, "local-same")
            t0 = time.perf_counter()
            rep = run_sweep(local, out=workdir / "local-same", workers=2, quiet=True, log=lambda *_: None)
            rows.append(_figures(rep, "local (same runs)", m, time.perf_counter() - t0))
    finally:
        subprocess.run(["bash", str(script), "stop", str(cluster)], capture_output=True, timeout=120)
    return rows


@register("sweep-warm")
def sweep_warm_bench(quick: bool, workdir: Path) -> list[dict]:
    """The same 20 smoke runs (6 with --quick) of a local sweep on 2 workers, forked from one warm server
    (:mod:`wendel.sweep.warm`, the default) and as fresh interpreters (``WENDEL_SWEEP_WARM=0``), interleaved
    twice (cold, warm, cold, warm): per run the sweep's wall time and CPU seconds (user + system of every process
    it waited for: ``RUSAGE_CHILDREN``), the mean run wall time and the runs' summary wall time; the last row the
    warm / cold ratios of the medians."""
    import resource
    import statistics

    from ..sweep import run_sweep

    shutil.rmtree(workdir, ignore_errors=True)
    workdir.mkdir(parents=True)
    n = 6 if quick else 20
    sweep = _sweep_file(workdir, n, "runs")
    rows = []
    for k, warm in enumerate(("0", "1", "0", "1")):
        with environ(WENDEL_SWEEP_WARM=warm):
            ru0, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), time.perf_counter()
            rep = run_sweep(sweep, out=workdir / f"{k}-{'warm' if warm == '1' else 'cold'}", workers=2, quiet=True,
                            log=lambda *_: None)
            wall, ru = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
            row = _figures(rep, "local, warm" if warm == "1" else "local, cold", n, wall)
            row.update({"wall_per_run_s": wall / n, "cpu_per_run_s": (ru.ru_utime + ru.ru_stime - ru0.ru_utime - ru0.ru_stime) / n,
                        "load_average": os.getloadavg()[0]})
        rows.append(row)

    def med(label, key):
        return statistics.median(r[key] for r in rows if r["executor"] == label)
    rows.append({"executor": "warm / cold", **{f"{k}_ratio": med("local, warm", k) / med("local, cold", k)
                                              for k in ("wall_per_run_s", "cpu_per_run_s", "mean_run_wall", "sum_summary_wall")}})
    return rows
