"""Campaigns: ``wendel sweep SWEEP.toml`` runs a plan of scenes, on this machine or on SLURM.

Public API: :func:`prepare` (plan, validate and lay out a sweep), :func:`run_sweep` (run what is not done,
locally or through submitit), :func:`status` and :func:`collect` (read the run folders; sweep.csv and plots).
The run folders are the truth (see :mod:`wendel.sweep.folders`): "done" is read from each folder, the table
is collected from them, and a folder's name carries a hash of its resolved scene, the wendel version and
the FreeFEM version, so two parameter sets never share one.
"""

from __future__ import annotations

import json
import time
from collections import Counter
from pathlib import Path
from typing import TYPE_CHECKING

from .folders import DONE, FAILED, INTERRUPTED, PENDING, STALE, read_json, run_dir, state, write_json

if TYPE_CHECKING:
    from .plan import Sweep

__all__ = ["prepare", "run_sweep", "status", "collect", "load_sweep", "sweep_root"]


def __getattr__(name: str):
    """``Sweep``, ``flatten`` and ``load_sweep`` from :mod:`wendel.sweep.plan` on first use: the CLI imports this
    package to build its argument parser for every command, and the plan pulls in pydantic and the scene schema
    (0.3-0.6 s) that ``wendel run`` should not wait for before its picture process starts (issue 20)."""
    if name in ("Sweep", "flatten", "load_sweep"):
        from . import plan
        return getattr(plan, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def sweep_root(sweep_path: Path, out: Path | None = None) -> Path:
    """The sweep folder: ``out`` or results/sweeps/<sweep file stem>/."""
    from ..freefem import ROOT     # wendel.loop.RESULTS, without importing the loop (a re-run stays fast)

    return Path(out).resolve() if out else ROOT / "results" / "sweeps" / Path(sweep_path).stem


def prepare(sweep: Sweep, root: Path) -> dict:
    """Write plan.json and each run's scene file (scenes/<key>.toml); return the plan."""
    import tomli_w

    from .plan import flatten

    (root / "scenes").mkdir(parents=True, exist_ok=True)
    (root / "runs").mkdir(exist_ok=True)
    for r in sweep.runs:
        path = root / "scenes" / f"{r.key}.toml"
        text = (f"# run {r.key} of the sweep {sweep.path}\n# parameters: "
                + ", ".join(f"{k} = {v!r}" for k, v in r.params.items()) + "\n" + tomli_w.dumps(r.data))
        if not path.is_file() or path.read_text() != text:
            path.write_text(text)
    spec = sweep.spec
    grid = flatten(spec.grid)
    plan = {"sweep": str(sweep.path), "description": spec.description, "scene": str(sweep.scene_path),
            "parameters": sweep.keys, "outputs": spec.outputs,
            "reference_quantity": sweep.runs[0].resolved.get("reference", {}).get("quantity"),
            "grid2": grid if len(grid) == 2 and not spec.zip and spec.sample is None else None,
            "runs": [{"key": r.key, "params": r.params, "ranks": r.ranks} for r in sweep.runs]}
    if read_json(root / "plan.json") != plan:
        write_json(root / "plan.json", plan)
    return plan


def _root_and_plan(target: Path, out: Path | None = None) -> tuple[Path, dict]:
    """A sweep folder (holding plan.json) or a sweep file (planned again)."""
    target = Path(target)
    if target.is_dir():
        plan = read_json(target / "plan.json")
        if plan is None:
            raise FileNotFoundError(f"{target}: no plan.json (not a sweep folder)")
        return target.resolve(), plan
    from .plan import load_sweep

    sweep = load_sweep(target)
    root = sweep_root(target, out)
    return root, prepare(sweep, root)


def run_sweep(sweep_path: Path, out: Path | None = None, executor: str = "local", workers: int | None = None,
              slurm: dict | None = None, detach: bool = False, quiet: bool = False, log=print) -> dict:
    """Run every run of the sweep that is not done; return a report (counts, wall time, folder).

    Every planned scene is validated first (:class:`wendel.scene.SceneError` before anything runs).
    """
    t0 = time.perf_counter()
    from contextlib import closing, nullcontext

    from .warm import Warm, enabled
    # the warm server's imports overlap the planning; it ends with the sweep
    with closing(Warm()) if executor == "local" and enabled() else nullcontext() as server:
        from .plan import load_sweep

        sweep = load_sweep(sweep_path)
        root = sweep_root(sweep_path, out)
        plan = prepare(sweep, root)
        states = {e["key"]: state(run_dir(root, e["key"]))[0] for e in plan["runs"]}
        todo = [k for k, s in states.items() if s != DONE]
        counts = Counter(states.values())
        log(f"sweep {sweep.path.name}: {len(plan['runs'])} runs in {root}: {counts[DONE]} done, "
            f"{counts[FAILED]} failed before (re-run), {counts[INTERRUPTED]} interrupted (resumed), "
            f"{counts[PENDING] + counts[STALE]} to start")
        report = {"root": root, "runs": len(plan["runs"]), "skipped": counts[DONE], "todo": len(todo)}
        if todo and executor == "local":
            from .local import default_workers, run_local

            lock = _lock(root)
            jobs = read_json(root / "slurm" / "jobs.json")
            if jobs and any(k in jobs for k in todo):       # run here now: earlier SLURM jobs no longer speak for them
                write_json(root / "slurm" / "jobs.json", {k: v for k, v in jobs.items() if k not in todo})
            n = workers or sweep.spec.workers or default_workers(max(r.ranks for r in sweep.runs))
            try:
                outcomes = run_local(root, todo, n, skipped=counts[DONE], quiet=quiet, warm=server)
            finally:
                lock.close()
            report["outcomes"] = outcomes
            report["workers"] = n
        elif todo and executor == "slurm":
            from . import slurm as slurm_exec
            from .plan import Slurm
            opts = Slurm.model_validate({**sweep.spec.slurm.model_dump(),       # the command line's values validated too
                                         **{k: v for k, v in (slurm or {}).items() if v is not None}})
            report["jobs"] = slurm_exec.submit(root, plan, todo, opts, log=log)
            if not detach:
                slurm_exec.wait(root, plan, quiet=quiet)
        elif todo:
            raise ValueError(f"unknown executor {executor!r}; valid: local, slurm")
        report["wall"] = time.perf_counter() - t0
        if not (executor == "slurm" and detach):
            rows, csv_path, changed = collect_into(root, plan)
            report["rows"] = rows
            report["csv"] = csv_path
        return report


def _lock(root: Path):
    """One local sweep at a time in a folder (an exclusive lock on ``root/.lock``, released at exit)."""
    import fcntl

    f = open(root / ".lock", "w")
    try:
        fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        f.close()
        raise ValueError(f"{root}: another wendel sweep is running in this folder") from None
    return f


def collect_into(root: Path, plan: dict, force: bool = False):
    """sweep.csv from the folders; plots redrawn when the table changed (or ``force``)."""
    from .table import collect as collect_table, plots

    rows, path, changed = collect_table(root, plan)
    if changed or force:
        plots(root, plan, rows)
    return rows, path, changed


def status(target: Path, out: Path | None = None) -> tuple[Path, Counter, list[dict]]:
    """Counts by status from the folders (and, for SLURM sweeps, the scheduler's queue and accounting)."""
    root, plan = _root_and_plan(target, out)
    live = {}
    if (root / "slurm" / "jobs.json").is_file():
        from . import slurm as slurm_exec

        live = slurm_exec.reconcile(root, plan)
    rows = []
    for e in plan["runs"]:
        s, msg = state(run_dir(root, e["key"]))
        if e["key"] in live and s not in (DONE, FAILED):
            s = live[e["key"]]
        rows.append({"key": e["key"], "status": s, "message": msg})
    return root, Counter(r["status"] for r in rows), rows


def collect(target: Path, out: Path | None = None) -> tuple[Path, list[dict]]:
    """Write sweep.csv and the plots of a sweep from its folders; return (csv path, rows)."""
    root, plan = _root_and_plan(target, out)
    if (root / "slurm" / "jobs.json").is_file():
        from . import slurm as slurm_exec

        slurm_exec.reconcile(root, plan)
    rows, path, _ = collect_into(root, plan, force=True)
    return path, rows
