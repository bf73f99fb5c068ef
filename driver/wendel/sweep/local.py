"""Run the pending runs of a sweep on this machine: N at a time, each ``wendel run`` in its own process
group, with a live progress display (done, running, failed, ETA). Ctrl-C stops every run (SIGINT: FreeFEM is
stopped, checkpoints stay) and leaves a sweep that the next ``wendel sweep`` resumes.
"""

from __future__ import annotations

import os
import threading
import time
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from pathlib import Path

from .folders import DONE, Stopped, execute, stop_process


def default_workers(ranks: int) -> int:
    """Cores divided by the MPI ranks of one run (at least 1).

    >>> default_workers(10**6)
    1
    """
    return max(1, (os.cpu_count() or 1) // max(1, ranks))


def run_local(root: Path, keys: list[str], workers: int, skipped: int = 0, quiet: bool = False,
              warm=None) -> list[dict]:
    """Run ``keys`` (none of them done) ``workers`` at a time; return one outcome dict per finished run.

    Raises KeyboardInterrupt after stopping every run when interrupted. ``warm``: the runs are forked from
    that server (:mod:`wendel.sweep.warm`; :func:`wendel.sweep.run_sweep` starts one unless
    ``WENDEL_SWEEP_WARM=0``), else each is a subprocess.
    """
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    stop = threading.Event()
    procs: dict[str, object] = {}
    lock = threading.Lock()
    outcomes: list[dict] = []
    running: set[str] = set()

    def one(key: str) -> dict:
        def started(proc):
            with lock:
                procs[key] = proc
                running.add(key)
        try:
            return execute(root, key, on_start=started, stop=stop, warm=warm)
        finally:
            with lock:
                procs.pop(key, None)
                running.discard(key)

    console = Console(stderr=True, quiet=quiet)
    columns = [TextColumn("[bold]sweep"), BarColumn(), MofNCompleteColumn(),
               TextColumn("done {task.fields[done]}  running {task.fields[running]}  failed {task.fields[failed]}"),
               TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn()]
    total = len(keys) + skipped
    done = failed = 0
    with Progress(*columns, console=console, transient=False) as bar:
        task = bar.add_task("sweep", total=total, completed=skipped, done=skipped, running=0, failed=0)
        pool = ThreadPoolExecutor(max_workers=workers)
        futures = {pool.submit(one, k): k for k in keys}
        pending = set(futures)
        try:
            while pending:
                finished, pending = wait(pending, timeout=0.5, return_when=FIRST_COMPLETED)
                for f in finished:
                    try:
                        out = f.result()
                    except Stopped:
                        continue
                    outcomes.append(out)
                    if out["status"] == DONE:
                        done += 1
                    else:
                        failed += 1
                        console.print(f"[red]failed[/red] {out['key']}: {out['message']}")
                with lock:
                    n_running = len(running)
                bar.update(task, completed=skipped + done + failed, done=skipped + done, running=n_running, failed=failed)
        except KeyboardInterrupt:
            stop.set()
            for f in futures:
                f.cancel()
            with lock:
                live = list(procs.values())
            console.print(f"stopping {len(live)} run(s); the sweep resumes with the same command")
            threads = [threading.Thread(target=stop_process, args=(p,)) for p in live]
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            pool.shutdown(wait=True, cancel_futures=True)
            raise
        pool.shutdown(wait=True)
    return outcomes
