"""Run a sweep on SLURM through submitit job arrays.

Each run is one task of an array (``sbatch --array``, at most ``parallelism`` at a time), chunked below the
cluster's MaxArraySize; with ``slurm.runs_per_task`` = k, k runs are one task (the scheduler's start per task
shared, the runs forked from one warm process). The task calls :func:`wendel.sweep.folders.execute`, the same code as a local
run: it resumes an interrupted run from its checkpoint. The job is ``Checkpointable``: on timeout or
preemption submitit requeues it and the run resumes. A run that fails records its message in its folder;
a job the scheduler killed (scancel, out of memory, node failure) is recorded failed by :func:`reconcile`,
which reads ``squeue`` and ``sacct`` (never waits on a job's result: without accounting it never comes).
Job ids are in ``<sweep>/slurm/jobs.json``; submitit's own files in ``<sweep>/slurm/<job>/``.
"""

from __future__ import annotations

import re
import subprocess
import time
from pathlib import Path

import submitit

from .folders import DONE, FAILED, INTERRUPTED, STALE, execute, mark_failed, move_aside, read_json, run_dir, state, write_json

LIVE = {"PENDING", "RUNNING", "REQUEUED", "REQUEUE_HOLD", "REQUEUE_FED", "CONFIGURING", "COMPLETING", "SUSPENDED",
        "RESIZING", "SIGNALING", "STAGE_OUT", "RESV_DEL_HOLD", "STOPPED"}


REQUEUE_WAIT = 30.0
"""s a task whose run was killed by a signal waits for its own signal (and submitit's requeue) before it ends."""


class RunJob(submitit.helpers.Checkpointable):
    """Runs of a sweep as one SLURM task (``slurm.runs_per_task`` of them, one after the other; more than one
    forked from a warm process, :mod:`wendel.sweep.warm`); requeued on timeout or preemption: the runs done are
    skipped, the interrupted one resumes from its checkpoint."""

    def __call__(self, root: str, keys: list[str] | str) -> list[dict]:
        from contextlib import closing, nullcontext

        from .warm import Warm, enabled

        keys = [keys] if isinstance(keys, str) else keys    # a job submitted before runs_per_task, requeued
        results = []
        with closing(Warm()) if len(keys) > 1 and enabled() else nullcontext() as server:
            for key in keys:
                results.append(execute(Path(root), key, killed_is_failure=False, warm=server))
                if results[-1]["status"] == INTERRUPTED:
                    # SLURM signals every process of the task (USR2 before a time limit or a preemption): the
                    # run's own process can die of it before this one's handler (submitit's requeue) has run;
                    # returning now would end the job as done, unrequeued (seen once in a CI run). Wait here
                    # for the signal and the requeue.
                    time.sleep(REQUEUE_WAIT)   # a signal's handler runs during it; the sleep then goes on (PEP 475)
                    break
        return results


def max_array_size() -> int:
    """The cluster's MaxArraySize (``scontrol show config``; 1001 when it cannot be read)."""
    try:
        out = subprocess.run(["scontrol", "show", "config"], capture_output=True, text=True, timeout=30).stdout
        m = re.search(r"^MaxArraySize\s*=\s*(\d+)", out, re.M)
        return int(m.group(1)) if m else 1001
    except (OSError, subprocess.SubprocessError):
        return 1001


def submit(root: Path, plan: dict, keys: list[str], opts, log=print) -> dict:
    """Submit ``keys`` (skipping those whose job is still queued or running); return {key: job id}."""
    jobs = read_json(root / "slurm" / "jobs.json") or {}
    live = reconcile(root, plan)
    keys = [k for k in keys if live.get(k) not in ("queued", "running")]
    if not keys:
        log("every run that is not done is queued or running already")
        return {}
    for k in keys:                       # a failed attempt is moved aside now: the run is pending until its job runs
        if state(run_dir(root, k))[0] in (FAILED, STALE):
            move_aside(root, k)
    ranks = {e["key"]: e["ranks"] for e in plan["runs"]}
    executor = submitit.SlurmExecutor(folder=root / "slurm" / "%j", max_num_timeout=5)
    params = {"time": opts.time, "mem": opts.mem, "array_parallelism": opts.parallelism,
              "cpus_per_task": opts.cpus_per_run or max(ranks[k] for k in keys), "job_name": f"wendel-{root.name}",
              "stderr_to_stdout": True}
    if opts.partition:
        params["partition"] = opts.partition
    executor.update_parameters(**params)
    per = opts.runs_per_task
    tasks = [keys[i:i + per] for i in range(0, len(keys), per)]
    chunk = max(1, max_array_size() - 1)
    submitted = {}
    for i in range(0, len(tasks), chunk):
        part = tasks[i:i + chunk]
        with executor.batch():
            handles = [executor.submit(RunJob(), str(root), t) for t in part]
        submitted.update({k: h.job_id for t, h in zip(part, handles) for k in t})
    jobs.update(submitted)
    write_json(root / "slurm" / "jobs.json", jobs)
    arrays = sorted({j.split("_")[0] for j in submitted.values()})
    log(f"submitted {len(submitted)} run(s) as array job(s) {', '.join(arrays)} "
        f"({len(tasks)} task(s) of {per} run(s), {opts.parallelism} at a time, {opts.time} min, {opts.mem} each)")
    return submitted


def _expand(jobid: str) -> list[str]:
    """``12_[0-2,5%2]`` -> 12_0, 12_1, 12_2, 12_5; other ids unchanged.

    >>> _expand("12_[0-2,5%2]")
    ['12_0', '12_1', '12_2', '12_5']
    """
    m = re.fullmatch(r"(\d+)_\[([^\]]+)\]", jobid)
    if not m:
        return [jobid]
    out = []
    for part in m.group(2).split("%")[0].split(","):
        a, _, b = part.partition("-")
        out += [f"{m.group(1)}_{i}" for i in range(int(a), int(b or a) + 1)]
    return out


def job_states(job_ids: list[str]) -> dict[str, str]:
    """State of each job: from ``squeue`` (jobs the controller still knows), else ``sacct``."""
    arrays = sorted({j.split("_")[0] for j in job_ids})
    found: dict[str, str] = {}
    if not arrays:
        return found
    for cmd in (["squeue", "-h", "-r", "-t", "all", "-j", ",".join(arrays), "-o", "%i %T"],
                ["sacct", "-n", "-P", "-X", "-j", ",".join(arrays), "-o", "JobID,State"]):
        try:
            out = subprocess.run(cmd, capture_output=True, text=True, timeout=60).stdout
        except (OSError, subprocess.SubprocessError):
            continue
        for line in out.splitlines():
            parts = line.replace("|", " ").split()
            if len(parts) < 2:
                continue
            for j in _expand(parts[0]):
                found.setdefault(j, parts[1].split()[0])   # "CANCELLED by 0" -> CANCELLED
    return found


def reconcile(root: Path, plan: dict) -> dict[str, str]:
    """Compare the folders with the scheduler: record killed jobs as failed; return {key: queued|running}
    for the runs whose job is alive (a complete run too, until its task has written its sweep.json, so that a
    table collected when nothing is live has every run's ``run_wall``)."""
    jobs = read_json(root / "slurm" / "jobs.json") or {}
    planned = {e["key"] for e in plan["runs"]}
    jobs = {k: j for k, j in jobs.items() if k in planned}
    states = job_states(list(jobs.values()))
    live = {}
    for key, job in jobs.items():
        status, _ = state(run_dir(root, key))
        s = states.get(job)
        if status == DONE and s in LIVE and (read_json(run_dir(root, key) / "sweep.json") or {}).get("status") != DONE:
            live[key] = "running"       # complete, but its task has not yet written sweep.json (the run's wall time)
            continue
        if status in (DONE, FAILED):
            continue
        if s in LIVE:
            live[key] = "queued" if s in ("PENDING", "REQUEUED", "REQUEUE_HOLD") else "running"
        elif s == "COMPLETED":
            mark_failed(run_dir(root, key), f"SLURM job {job} ended without completing the run", job=job)
        elif s is not None:
            mark_failed(run_dir(root, key), f"SLURM job {job}: {s}", job=job)
        else:
            mark_failed(run_dir(root, key), f"SLURM job {job} is neither in the queue nor in the accounting", job=job)
    return live


def wait(root: Path, plan: dict, poll: float = 2.0, quiet: bool = False) -> None:
    """Show progress until no job of the sweep is queued or running (Ctrl-C stops waiting, not the jobs)."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    console = Console(stderr=True, quiet=quiet)
    columns = [TextColumn("[bold]sweep (SLURM)"), BarColumn(), MofNCompleteColumn(),
               TextColumn("done {task.fields[done]}  queued {task.fields[queued]}  running {task.fields[running]}  "
                          "failed {task.fields[failed]}"), TimeElapsedColumn()]
    total = len(plan["runs"])
    try:
        with Progress(*columns, console=console) as bar:
            task = bar.add_task("sweep", total=total, done=0, queued=0, running=0, failed=0)
            while True:
                live = reconcile(root, plan)
                st = [state(run_dir(root, e["key"]))[0] for e in plan["runs"]]
                done, failed = st.count(DONE), st.count(FAILED)
                queued = sum(1 for v in live.values() if v == "queued")
                bar.update(task, completed=done + failed, done=done, failed=failed, queued=queued,
                           running=len(live) - queued)
                if not live:
                    return
                time.sleep(poll)
    except KeyboardInterrupt:
        console.print("stopped waiting; the jobs go on: `wendel sweep status` / `wendel sweep collect`")
        raise
