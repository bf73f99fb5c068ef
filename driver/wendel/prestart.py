"""FreeFEM launches started ahead of their inputs (issue 20).

A run whose launches follow one another with driver work between them (the drilling loop: remesh and
transfer, then one launch per removal step) paid each launch's start again on its critical path: the
process and Open MPI's singleton, the plugins, compiling the entry script (0.1-0.2 s here; 51 launches of
drilling-deep-rz). :func:`start` starts the next launch as soon as its command line is known; FreeFEM
compiles and then waits at its gate (``-DWITHGATE=1``, ``edp/lib/common.idp``) before it reads any file.
:func:`wendel.freefem.run`, given it as ``started``, says "go" on its stdin when the inputs are written, and
times the launch from there. A launch whose command line turned out otherwise is stopped unused
(:func:`abandon`) and started as usual: the launch FreeFEM runs is always the one asked for.
``WENDEL_PRESTART=0``: no launch is started ahead (every launch starts when asked, as before).

``start(..., early=True)``: the launch is started beside the solve of the launch before it (the drilling loop:
at the start of each removal step's launch), at the lowest CPU priority (nice 19), so that its start (0.15-0.3
s of CPU: the process, MPI, the plugins, compiling) takes only CPU the solve leaves unused; ``run`` gives it
the driver's priority back (every thread) when it says "go". Without the right to raise a priority again
(not root and no ``RLIMIT_NICE`` for it) ``early`` is not honoured (None: the caller starts it later).
"""

from __future__ import annotations

import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

from .freefem import _command, _kill, _popen


@dataclass
class Started:
    """A launch started ahead of its inputs: FreeFEM waits at its gate for "go" on stdin."""

    entry: str
    options: list[str]
    out_dir: Path
    proc: subprocess.Popen
    cmd: list[str]
    session: str
    log: Path
    nice: int | None = None     # the priority to give it back at "go" (started early at nice 19), or None


EARLY_NICE = 19
"""The priority of a launch started early, beside a solve (``start(..., early=True)``)."""


def can_start_early() -> bool:
    """Whether a launch started at nice 19 can be given this process's priority back (:func:`start`'s
    ``early``): root, or an ``RLIMIT_NICE`` that allows it; ``WENDEL_PRESTART`` not ``0`` or ``late``."""
    if os.environ.get("WENDEL_PRESTART", "1") in ("0", "late"):
        return False
    if os.geteuid() == 0:
        return True
    try:
        import resource
        soft = resource.getrlimit(resource.RLIMIT_NICE)[0]
    except (ImportError, AttributeError, OSError, ValueError):
        return False
    return soft == resource.RLIM_INFINITY or 20 - soft <= os.getpriority(os.PRIO_PROCESS, 0)


def start(entry: str, options: list[str], out_dir: Path, ranks: int = 1, log: Path | None = None,
          early: bool = False) -> Started | None:
    """Start the launch :func:`wendel.freefem.run` will be asked for with these arguments, before its input
    files exist; FreeFEM waits until ``run`` says "go" on its stdin, :func:`abandon` stops it unused. One rank
    only (None otherwise: stdin reaches one rank of ``mpirun``). ``early``: beside a solve, at nice 19 until
    "go" (None when :func:`can_start_early` says no)."""
    if os.environ.get("WENDEL_PRESTART", "1") == "0" or (early and not can_start_early()):
        return None
    script, cmd, env, session, singleton = _command(entry, options, out_dir, ranks, gate=True)
    if not singleton:
        shutil.rmtree(session, ignore_errors=True)
        return None
    nice = None
    if early:
        nice = os.getpriority(os.PRIO_PROCESS, 0)
        cmd = ["nice", "-n", str(max(EARLY_NICE - nice, 0)), *cmd]
    log = log or out_dir / "freefem.log"
    proc = _popen(cmd, env, out_dir, log, subprocess.PIPE)
    return Started(entry, list(options), out_dir, proc, cmd, session, log, nice)


def abandon(started: Started | None) -> None:
    """Stop a launch started by :func:`start` that is not used (its process group, then its MPI folder)."""
    if started is None:
        return
    _kill(started.proc)
    if started.proc.stdin:
        started.proc.stdin.close()
    shutil.rmtree(started.session, ignore_errors=True)
