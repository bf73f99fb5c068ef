"""gmsh with a time limit: a remesh made in a worker process that is stopped when it takes too long.

gmsh can hang on the boundary of a badly deformed body: measured on the titanium cut with F-bar and conduction
(session 27), remesh 162 at 1,380 um sat in ``gmsh.model.mesh.generate`` for 11 minutes at 100 % CPU until the run
was killed. A call into gmsh cannot be interrupted from Python (a signal waits for the C++ call to return), so with
``remesh.mesh_timeout`` the remesh's :func:`wendel.remesh.mesher.remesh` runs in one worker process per run (a fresh
interpreter, started at the first remesh and reused; gmsh's own output to fd 1 goes to /dev/null there, as in the
driver), its arguments and report passed by pickle. When it has not answered within the limit the worker is
killed and :class:`MeshTimeout` raised: :func:`wendel.remesh.again.made_or_failed` then meshes the body with the
next gmsh 2D algorithm. The worker's gmsh is the driver's (same version, one thread, a new session per mesh), so
its mesh is the one the driver would have made.
"""

from __future__ import annotations

import atexit
import os
import pickle
import select
import subprocess
import sys

_QUIET = r"""
import os, sys
answer = os.fdopen(os.dup(1), "{mode}", buffering={buffering})      # the protocol; gmsh prints to fd 1
null = os.open(os.devnull, os.O_WRONLY)
os.dup2(null, 1)
os.close(null)
"""

_WORKER = r"""
import pickle
from wendel.remesh import mesher
while True:
    try:
        args, kwargs = pickle.load(sys.stdin.buffer)
    except EOFError:
        break
    try:
        result = (True, mesher.remesh(*args, **kwargs))
    except Exception as e:
        result = (False, str(e) if type(e) is ValueError else f"{type(e).__name__}: {e}")
    pickle.dump(result, answer)
    answer.flush()
"""


def gmsh_worker(body: str, text: bool = False) -> subprocess.Popen:
    """A fresh interpreter running ``body`` (Python source) on the driver's code, its requests on stdin, gmsh's
    output to fd 1 sent to /dev/null and its answers written to ``answer`` (the process's stdout; text or
    binary; text answers are line-buffered); stderr to /dev/null. Also the drilling loop's mesh worker (:class:`wendel.loop.ahead.Builder`)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))      # the driver's code
    code = _QUIET.format(mode="w" if text else "wb", buffering=1 if text else -1) + body
    return subprocess.Popen([sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=text, env=env)


class MeshTimeout(RuntimeError):
    """gmsh did not mesh the body within the time limit (not an OSError: a full disk is told apart)."""


class Worker:
    """:func:`wendel.remesh.mesher.remesh` in a worker process, ``timeout`` seconds at most a call."""

    def __init__(self, timeout: float):
        self.timeout = timeout
        self.proc: subprocess.Popen | None = None

    def __call__(self, *args, **kwargs) -> dict:
        if self.proc is None or self.proc.poll() is not None:
            self.proc = gmsh_worker(_WORKER)
        try:
            pickle.dump((args, kwargs), self.proc.stdin)
            self.proc.stdin.flush()
        except BrokenPipeError:         # the worker died since its last mesh: not a full disk (an OSError too)
            self.close()
            raise RuntimeError("the remesh worker process had ended (gmsh crashed?)") from None
        if not select.select([self.proc.stdout], [], [], self.timeout)[0]:
            self.close()
            raise MeshTimeout(f"gmsh did not mesh the deformed body within remesh.mesh_timeout = {self.timeout:g} s "
                              f"(stopped)")
        try:
            ok, result = pickle.load(self.proc.stdout)
        except (EOFError, pickle.UnpicklingError):
            self.close()
            raise RuntimeError("the remesh worker process ended without a mesh (gmsh crashed?)") from None
        if not ok:
            raise ValueError(result)
        return result

    def close(self) -> None:
        if self.proc is not None:
            if self.proc.poll() is None:
                self.proc.kill()
            self.proc.wait()
            self.proc.stdin.close()
            self.proc.stdout.close()
            self.proc = None


_WORKERS: dict[float, Worker] = {}


def mesher(timeout: float | None):
    """The remesh function with ``timeout`` seconds at most a mesh (a worker kept for the process), or None (gmsh in
    the driver) without one."""
    if timeout is None:
        return None
    if timeout not in _WORKERS:
        _WORKERS[timeout] = Worker(timeout)
    return _WORKERS[timeout]


@atexit.register
def _close() -> None:
    for w in _WORKERS.values():
        w.close()
