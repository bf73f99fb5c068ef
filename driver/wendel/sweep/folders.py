"""A sweep on disk, and one run of it: the run folders are the truth.

``<sweep>/plan.json``              the planned runs (parameters and folder names), written by ``wendel sweep``
``<sweep>/scenes/<key>.toml``      the scene of each run (smoke size and parameters applied)
``<sweep>/runs/<key>/``            the run folder of ``wendel run`` (summary.json says whether it completed)
``<sweep>/runs/<key>/sweep.json``  how the last attempt ended: status, wall time, exit code, message
``<sweep>/logs/<key>.log``         what ``wendel run`` printed
``<sweep>/failed/<key>-N/``        earlier failed attempts, moved aside before a fresh start (nothing deleted)

A run is *done* when its summary.json says completed; *failed* when sweep.json says so (or the scheduler
killed it); *interrupted* when it has a checkpoint and neither (it resumes with ``wendel run --resume``);
*pending* when its folder does not exist.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from ..freefem import alive, terminate

DONE, FAILED, INTERRUPTED, PENDING, STALE = "done", "failed", "interrupted", "pending", "stale"
EXIT_INTERRUPTED = 130
"""``wendel run`` stopped by Ctrl-C or SIGTERM: FreeFEM stopped, the run resumable."""


def run_dir(root: Path, key: str) -> Path:
    return root / "runs" / key


def read_json(path: Path) -> dict | None:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def write_json(path: Path, data: dict) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=1))
    os.replace(tmp, path)


def state(folder: Path) -> tuple[str, str]:
    """(status, message) of a run folder, read from the folder only."""
    if not folder.is_dir() or not any(folder.iterdir()):
        return PENDING, ""
    summary = read_json(folder / "summary.json")
    if summary and summary.get("completed"):
        return DONE, ""
    record = read_json(folder / "sweep.json") or {}
    if record.get("status") == FAILED:
        return FAILED, record.get("message", "")
    if (folder / "checkpoint.json").is_file():
        return INTERRUPTED, ""
    return STALE, "a run folder without checkpoint (stopped while meshing)"


def mark_failed(folder: Path, message: str, **extra) -> None:
    """Record a failure in the run folder (made if missing)."""
    folder.mkdir(parents=True, exist_ok=True)
    old = read_json(folder / "sweep.json") or {}
    write_json(folder / "sweep.json", {**old, "status": FAILED, "message": message, **extra,
                                       "ended": time.strftime("%Y-%m-%dT%H:%M:%S%z")})


def move_aside(root: Path, key: str) -> None:
    src = run_dir(root, key)
    (root / "failed").mkdir(exist_ok=True)
    n = 1
    while (root / "failed" / f"{key}-{n}").exists():
        n += 1
    os.replace(src, root / "failed" / f"{key}-{n}")


def _failure_message(log: Path, rc: int) -> str:
    """The ``wendel: ...`` lines of the log (the CLI's own message), else its tail."""
    try:
        lines = log.read_text(errors="replace").strip().splitlines()
    except OSError:
        lines = []
    ours = [i for i, l in enumerate(lines) if l.startswith(("wendel: run failed", "wendel: bad"))]
    if ours:
        return " ".join(l.strip() for l in lines[ours[-1]:][:4])[:500]
    tail = " | ".join(lines[-3:])
    return f"exit code {rc}: {tail}"[:500]


def _signal_name(rc: int) -> str:
    try:
        return signal.Signals(-rc).name
    except ValueError:
        return f"signal {-rc}"


class Stopped(Exception):
    """The sweep is being stopped (Ctrl-C): the run was interrupted and stays resumable."""


def execute(root: Path, key: str, on_start=None, stop: threading.Event | None = None,
            killed_is_failure: bool = True, warm=None) -> dict:
    """Bring the run ``key`` of the sweep in ``root`` to an end: skip it when done, resume it when
    interrupted, start it afresh otherwise (failed attempts moved aside). Runs ``wendel run`` as a
    subprocess in its own process group; ``on_start(proc)`` is called with it (to stop it on Ctrl-C).

    ``warm``: a :class:`wendel.sweep.warm.Warm` server that forks the run instead (the same arguments, log and
    process group), or None.

    A run killed by a signal (or stopped by one: exit 130) is failed, unless ``killed_is_failure`` is false (under SLURM: the scheduler
    killed it, to requeue it or for good, and :func:`wendel.sweep.slurm.reconcile` reads which); it then
    stays interrupted, to be resumed.

    Returns ``{"key", "status", "wall", "message", "action"}``; raises :class:`Stopped` when stopped.
    """
    folder = run_dir(root, key)
    status, _ = state(folder)
    if status == DONE:
        return {"key": key, "status": DONE, "wall": 0.0, "message": "", "action": "skipped"}
    if status in (FAILED, STALE):
        move_aside(root, key)
    stop_leftovers(folder)
    if status == INTERRUPTED:
        action, args = "resumed", ["--resume", str(folder)]
    else:
        action, args = "started", [str(root / "scenes" / f"{key}.toml"), "--out", str(folder)]
    if stop is not None and stop.is_set():
        raise Stopped(key)
    log = root / "logs" / f"{key}.log"
    log.parent.mkdir(parents=True, exist_ok=True)
    cmd = [sys.executable, "-m", "wendel.cli", "run", *args]
    t0 = time.perf_counter()
    with open(log, "a") as flog:
        flog.write(f"$ {' '.join(cmd)}\n")
        flog.flush()
        proc = warm.spawn(["run", *args], log) if warm is not None else None
        if proc is None:
            if warm is not None:
                flog.write("(the warm server is gone: started as a subprocess)\n")
                flog.flush()
            proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=flog, stderr=subprocess.STDOUT,
                                    start_new_session=True)
        if on_start is not None:
            on_start(proc)
        try:
            rc = proc.wait()
        except BaseException:
            stop_process(proc)
            raise
    wall = time.perf_counter() - t0
    status, _ = state(folder)
    if status == DONE:
        old = read_json(folder / "sweep.json") or {}
        write_json(folder / "sweep.json", {"status": DONE, "wall": old.get("wall", 0.0) + wall, "exit": rc,
                                           "attempts": old.get("attempts", 0) + 1, "action": action,
                                           "warm": not isinstance(proc, subprocess.Popen),
                                           "ended": time.strftime("%Y-%m-%dT%H:%M:%S%z")})
        return {"key": key, "status": DONE, "wall": wall, "message": "", "action": action}
    if stop is not None and stop.is_set():
        raise Stopped(key)
    killed = rc < 0 or rc == EXIT_INTERRUPTED
    reason = "stopped by SIGINT or SIGTERM (exit 130)" if rc == EXIT_INTERRUPTED else f"killed by {_signal_name(rc)}"
    if killed and not killed_is_failure:
        return {"key": key, "status": INTERRUPTED, "wall": wall, "message": reason, "action": action}
    message = reason if killed else _failure_message(log, rc)
    mark_failed(folder, message, exit=rc, wall=wall, action=action)
    return {"key": key, "status": FAILED, "wall": wall, "message": message, "action": action}


def descendants(pid: int) -> list[int]:
    """Every process below ``pid`` (from /proc), children first.

    >>> child = subprocess.Popen(["sleep", "5"])
    >>> child.pid in descendants(os.getpid()), child.kill(), child.wait()
    (True, None, -9)
    """
    children: dict[int, list[int]] = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                ppid = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(d.name))
    out, todo = [], [pid]
    while todo:
        for c in children.get(todo.pop(), []):
            out.append(c)
            todo.append(c)
    return out


def stop_leftovers(folder: Path) -> list[int]:
    """Stop processes of an earlier attempt that still work in ``folder`` (on this host): an MPI launch runs
    in its own session and outlives a ``wendel run`` killed by a signal where the scheduler tracks processes
    by their parents (proctrack/linuxproc; proctrack/cgroup kills them). Returns their pids."""
    mark = str(folder) + "/"
    own = {os.getpid(), *descendants(os.getpid())}
    found = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit() and int(d.name) not in own:
            try:
                cmd = (d / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
            except OSError:
                continue
            if mark in cmd or cmd.rstrip().endswith(str(folder)):
                found.append(int(d.name))
    terminate(found, grace=5.0)
    return found


def stop_process(proc: subprocess.Popen, grace: float = 10.0) -> None:
    """Stop a ``wendel run`` subprocess and everything it started, also the MPI launches in their own sessions:
    SIGINT to its process group first (a run that handles it stops FreeFEM itself; the checkpoint stays),
    then SIGTERM and SIGKILL to the process groups of every descendant seen before."""
    tree = descendants(proc.pid)
    groups = set()
    for p in tree:
        try:
            groups.add(os.getpgid(p))
        except ProcessLookupError:
            pass
    try:
        os.killpg(proc.pid, signal.SIGINT)
    except ProcessLookupError:
        pass
    try:
        proc.wait(timeout=grace)
    except subprocess.TimeoutExpired:
        pass
    for sig in (signal.SIGTERM, signal.SIGKILL):
        left = [p for p in [proc.pid, *tree] if alive(p)]
        if not left:
            return
        for g in groups | {proc.pid}:
            try:
                os.killpg(g, sig)
            except ProcessLookupError:
                pass
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline and any(alive(p) for p in left):
            try:
                proc.wait(timeout=0.1)
            except subprocess.TimeoutExpired:
                pass
