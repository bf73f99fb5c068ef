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


def start(entry: str, options: list[str], out_dir: Path, ranks: int = 1, log: Path | None = None) -> Started | None:
    """Start the launch :func:`wendel.freefem.run` will be asked for with these arguments, before its input
    files exist; FreeFEM waits until ``run`` says "go" on its stdin, :func:`abandon` stops it unused. One rank
    only (None otherwise: stdin reaches one rank of ``mpirun``)."""
    if os.environ.get("WENDEL_PRESTART", "1") == "0":
        return None
    script, cmd, env, session, singleton = _command(entry, options, out_dir, ranks, gate=True)
    if not singleton:
        shutil.rmtree(session, ignore_errors=True)
        return None
    log = log or out_dir / "freefem.log"
    proc = _popen(cmd, env, out_dir, log, subprocess.PIPE)
    return Started(entry, list(options), out_dir, proc, cmd, session, log)


def abandon(started: Started | None) -> None:
    """Stop a launch started by :func:`start` that is not used (its process group, then its MPI folder)."""
    if started is None:
        return
    _kill(started.proc)
    if started.proc.stdin:
        started.proc.stdin.close()
    shutil.rmtree(started.session, ignore_errors=True)
