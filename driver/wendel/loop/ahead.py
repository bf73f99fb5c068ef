"""The next removal step's mesh, built while FreeFEM solves this one (issue 20).

The drilling loop's body at a removal step depends only on the tip depth the plan gives, not on the
solution: gmsh (OCC boolean and a graded mesh, 40-50 ms per step of the (r, z) section here, much more in
3D) can run beside FreeFEM's solve of the step before instead of after it. :class:`Builder` keeps one worker
process for the run (a fresh interpreter started with the first launch, so gmsh never shares the driver's
process, signals or stdout; not ``multiprocessing``, whose spawn would import the caller's main script
again) and builds each mesh there into a temporary name that is renamed when complete; :meth:`Builder.take`
waits for it. The worker's gmsh is the driver's (one thread, fixed seed, a new session per mesh), so the
file is the one the driver would have written. A worker that fails or dies: the step is meshed in the
driver as before.
"""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path

from ..remesh.limit import gmsh_worker

_WORKER = r"""
import json
from pathlib import Path
from wendel.meshes import drilling as geometry
for line in sys.stdin:
    job = json.loads(line)
    final = Path(job["path"])
    part = final.with_name(final.stem + ".part" + final.suffix)
    try:
        if job["kind"] == "section":
            geometry.drilled_section(part, **job["kwargs"])
        else:
            geometry.drilled(part, job["kind"], **job["kwargs"])
        os.replace(part, final)
        answer.write(json.dumps({"path": job["path"], "ok": True}) + "\n")
    except Exception as e:
        answer.write(json.dumps({"path": job["path"], "ok": False, "error": repr(e)}) + "\n")
"""


class Builder:
    """Meshes built in one worker process, by path: :meth:`submit`, then :meth:`take`; :meth:`close` at the
    run's end. ``WENDEL_PRESTART=0``: nothing is built ahead (:meth:`submit` does nothing)."""

    def __init__(self):
        self.proc: subprocess.Popen | None = None
        self.pending: list[str] = []            # paths asked for, in order (the worker answers in order)
        self.taken = 0                          # meshes built ahead and used
        self.asked: set[str] = set()            # every path asked for (asked again: nothing to do)

    def submit(self, kind: str, path: Path, kwargs: dict) -> None:
        if os.environ.get("WENDEL_PRESTART", "1") == "0" or str(path) in self.asked:
            return
        self.asked.add(str(path))
        try:
            if self.proc is None:
                self.proc = gmsh_worker(_WORKER, text=True)
            self.proc.stdin.write(json.dumps({"kind": kind, "path": str(path), "kwargs": kwargs}) + "\n")
            self.proc.stdin.flush()
            self.pending.append(str(path))
        except OSError:         # no worker: the driver meshes
            self.close()

    def take(self, path: Path) -> bool:
        """Wait for the mesh of ``path`` if it is being built; True when it is there (False: build it)."""
        if str(path) not in self.pending:
            return False
        while self.pending:
            line = self.proc.stdout.readline()
            if not line:                    # the worker died
                self.close()
                return False
            done = json.loads(line)
            self.pending.remove(done["path"])
            if done["path"] == str(path):
                self.taken += done["ok"]
                return done["ok"]
        return False

    def close(self) -> None:
        if self.proc is not None:
            try:
                self.proc.stdin.close()
                self.proc.wait(timeout=30)
            except (OSError, subprocess.TimeoutExpired):
                self.proc.kill()
                self.proc.wait()
            self.proc.stdout.close()
            self.proc = None
        self.pending.clear()
