"""Warm starts for a local sweep (issue 20): one process imports the run's modules once and forks a child per
run, instead of a fresh interpreter per run that imports them again.

A smoke-size run spends most of its wall time outside its solve, and most of that is one Python with its
imports (0.37-0.62 s for the driver's, 0.8-1.1 s for the picture process's matplotlib and meshio, measured in
the README's "Time outside the solve") against a solve of 0.1-0.3 s. In a sweep of many small runs the same
imports are paid again by every run. :class:`Warm` starts :func:`serve` in a new interpreter once per sweep: it
imports the driver (``wendel.cli``, ``wendel.loop``, the scene schema) and the 2D picture's modules, then reads
one request per line (``{"id", "argv", "log", "cwd"}``) and forks; the child starts its own session (the sweep
stops it by its process group, as a ``wendel run`` subprocess), points its output at the run's log and calls
``wendel.cli.main`` with the run's arguments; its own picture process is forked from it in turn
(:func:`fork_painter`: the matplotlib imports are already there). The server reaps each child and answers
``{"id", "pid"}`` when it is forked and ``{"id", "rc"}`` when it ends (exit code as ``Popen``'s: negative for a
signal).

:class:`WarmRun` is the sweep's handle of such a child, with the part of ``subprocess.Popen``'s interface that
:func:`wendel.sweep.folders.execute` and :func:`~wendel.sweep.folders.stop_process` use (``pid``, ``wait``,
``poll``, ``returncode``). ``WENDEL_SWEEP_WARM=0``: every run a subprocess, as when the server dies.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading

FORKED = False
"""True in a run forked by the server: its modules, also matplotlib's, are imported (:func:`fork_painter`)."""


def enabled() -> bool:
    """Whether a local sweep uses warm starts: ``WENDEL_SWEEP_WARM`` 1 (default) or 0, anything else refused."""
    v = os.environ.get("WENDEL_SWEEP_WARM", "1")
    if v not in ("0", "1"):
        raise ValueError(f"WENDEL_SWEEP_WARM = {v!r}: 1 (fork each run from one warm process) or 0 (a fresh "
                         "interpreter per run)")
    return v == "1"


class WarmRun:
    """A run forked by the server: ``pid`` (its process group too), ``wait(timeout)``, ``poll()``,
    ``returncode`` once it ended."""

    def __init__(self, args: list[str]):
        self.args = args
        self.pid: int | None = None
        self.returncode: int | None = None
        self.started = threading.Event()
        self.ended = threading.Event()

    def poll(self) -> int | None:
        return self.returncode if self.ended.is_set() else None

    def wait(self, timeout: float | None = None) -> int:
        if not self.ended.wait(timeout):
            raise subprocess.TimeoutExpired(self.args, timeout)
        return self.returncode


class Warm:
    """The sweep's side of the server: :meth:`spawn` a run, :meth:`close` at the end (the server ends when its
    last child has ended)."""

    def __init__(self):
        self.proc = subprocess.Popen([sys.executable, "-c", "from wendel.sweep.warm import serve; serve()"],
                                     stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, text=True, start_new_session=True)
        self.lock = threading.Lock()
        self.runs: dict[int, WarmRun] = {}
        self.count = 0
        self.alive = True
        threading.Thread(target=self._read, daemon=True).start()

    def spawn(self, argv: list[str], log) -> WarmRun | None:
        """Fork ``wendel <argv>`` with its output appended to ``log``; None when the server is gone (the caller
        starts a subprocess instead)."""
        with self.lock:
            if not self.alive:
                return None
            self.count += 1
            run = self.runs[self.count] = WarmRun(["wendel", *argv])
            try:
                self.proc.stdin.write(json.dumps({"id": self.count, "argv": argv, "log": str(log),
                                                  "cwd": os.getcwd()}) + "\n")
                self.proc.stdin.flush()
            except (OSError, ValueError):
                self.alive = False
                self.runs.pop(self.count)
                return None
        run.started.wait()
        return run if run.pid is not None else None

    def _read(self) -> None:
        for line in self.proc.stdout:
            try:
                msg = json.loads(line)
            except ValueError:      # not the server's (it answers on its own descriptor; kept safe anyway)
                continue
            with self.lock:
                run = self.runs.get(msg["id"])
                if run is None:
                    continue
                if "pid" in msg:
                    run.pid = msg["pid"]
                    run.started.set()
                else:
                    run.returncode = msg["rc"]
                    self.runs.pop(msg["id"])
                    run.ended.set()
        with self.lock:         # the server is gone: what it had not forked falls back, what it had is lost
            self.alive = False
            for run in self.runs.values():
                if run.pid is None:
                    run.started.set()
                else:
                    run.returncode = -signal.SIGKILL
                    run.ended.set()
            self.runs.clear()

    def close(self) -> None:
        """End the server: at once if it forked nothing (it may still be importing), else when its last
        child has ended."""
        if self.count == 0:
            self.proc.kill()
        try:
            self.proc.stdin.close()
        except OSError:
            pass
        try:
            self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


def fork_painter(renderer: str):
    """A picture process forked from a warm run (its matplotlib is imported): a ``Popen``-like object with
    ``stdin``, ``stdout``, ``poll``, ``wait`` and ``kill``, serving :func:`wendel.results.pictures.serve_lines`;
    None where a fork is not safe or not warm (pyvista, another thread running): the caller starts a process."""
    if not FORKED or renderer != "matplotlib" or threading.active_count() != 1:
        return None
    to_child, from_parent = os.pipe()[::-1]
    from_child, to_parent = os.pipe()
    pid = os.fork()
    if pid == 0:
        code = 0
        try:
            os.setsid()
            os.dup2(from_parent, 0)
            os.dup2(to_parent, 1)
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, 2)
            for fd in (null, from_parent, to_parent, to_child, from_child):
                os.close(fd)
            from ..results.pictures import serve_lines
            serve_lines("matplotlib", open(0), open(1, "w"))
        except BaseException:   # noqa: BLE001 - the run sees the picture process end
            code = 1
        os._exit(code)
    os.close(from_parent)
    os.close(to_parent)
    return _Child(pid, os.fdopen(to_child, "w"), os.fdopen(from_child))


class _Child:
    """A forked child of this process, as much of ``subprocess.Popen`` as :class:`~wendel.results.pictures.Painter` uses."""

    def __init__(self, pid: int, stdin, stdout):
        self.pid, self.stdin, self.stdout, self.returncode = pid, stdin, stdout, None

    def poll(self) -> int | None:
        if self.returncode is None:
            pid, status = os.waitpid(self.pid, os.WNOHANG)
            if pid:
                self.returncode = os.waitstatus_to_exitcode(status)
        return self.returncode

    def wait(self, timeout: float | None = None) -> int:
        import time
        end = None if timeout is None else time.monotonic() + timeout
        while self.poll() is None:
            if end is not None and time.monotonic() >= end:
                raise subprocess.TimeoutExpired(["picture"], timeout)
            time.sleep(0.002)
        return self.returncode

    def kill(self) -> None:
        if self.returncode is None:
            os.kill(self.pid, signal.SIGKILL)


def _preload() -> None:
    """The modules a run imports (the driver's, the scene schema's, the 2D picture's)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot  # noqa: F401
    import meshio  # noqa: F401

    import wendel.cli  # noqa: F401
    import wendel.loop  # noqa: F401
    import wendel.results.pictures  # noqa: F401
    import wendel.scene  # noqa: F401


def _child(req: dict, keep: tuple[int, ...]) -> None:
    """In the forked child (``keep``: the server's descriptors, closed): the run's session, output, arguments."""
    global FORKED
    code = 1
    try:
        os.setsid()
        signal.set_wakeup_fd(-1)
        for fd in keep:
            os.close(fd)
        signal.signal(signal.SIGCHLD, signal.SIG_DFL)
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        null = os.open(os.devnull, os.O_RDONLY)
        os.dup2(null, 0)
        os.close(null)
        log = os.open(req["log"], os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        os.dup2(log, 1)
        os.dup2(log, 2)
        os.close(log)
        os.chdir(req["cwd"])
        FORKED = True
        sys.argv = ["wendel", *req["argv"]]
        from wendel.cli import leave, main
        try:
            code = main(req["argv"])
        except SystemExit as exc:
            code = exc.code if isinstance(exc.code, int) else 1
        leave(code)
    except BaseException:       # noqa: BLE001 - reported in the run's log
        import traceback

        traceback.print_exc()
    finally:
        os._exit(code if isinstance(code, int) else 1)


def serve() -> None:
    """The server: preload, then fork one run per request line; reap and report; end when stdin is closed and
    every child has ended."""
    import select

    signal.signal(signal.SIGINT, signal.SIG_IGN)      # the sweep stops the runs; it closes stdin to end this
    out = os.fdopen(os.dup(1), "w")                   # the answers; what an import prints goes to stderr
    os.dup2(2, 1)
    _preload()
    wake_r, wake_w = os.pipe()
    os.set_blocking(wake_r, False)
    os.set_blocking(wake_w, False)
    signal.signal(signal.SIGCHLD, lambda *_: None)
    signal.set_wakeup_fd(wake_w)
    children: dict[int, int] = {}
    buf, eof, fd = b"", False, sys.stdin.fileno()

    def say(msg: dict) -> None:
        out.write(json.dumps(msg) + "\n")
        out.flush()

    while not eof or children:
        try:
            ready, _, _ = select.select([wake_r] + ([] if eof else [fd]), [], [], 1.0)
        except InterruptedError:
            ready = []
        if wake_r in ready:
            try:
                os.read(wake_r, 4096)
            except BlockingIOError:
                pass
        if fd in ready:
            chunk = os.read(fd, 65536)
            eof = not chunk
            buf += chunk
            while b"\n" in buf:
                line, buf = buf.split(b"\n", 1)
                req = json.loads(line)
                out.flush()
                pid = os.fork()
                if pid == 0:
                    _child(req, (wake_r, wake_w, out.fileno()))
                children[pid] = req["id"]
                say({"id": req["id"], "pid": pid})
        while children:
            try:
                pid, status = os.waitpid(-1, os.WNOHANG)
            except ChildProcessError:
                break
            if pid == 0:
                break
            if pid in children:
                say({"id": children.pop(pid), "rc": os.waitstatus_to_exitcode(status)})

