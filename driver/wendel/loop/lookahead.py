"""What the drilling loop's next steps need of the meshes alone, found while FreeFEM solves (issue 20).

After a removal step's launch the driver located point sets in that step's mesh, on its critical path while
FreeFEM waited at its gate: the probes (the step's record), the removed slice's quadrature (the chips'
heat), the next mesh's nodes (the transfer) and its cells' quadrature points (the conservative transfer of
the temperature); and it waited for the mesh worker (:mod:`wendel.loop.ahead`) and read and judged the next
mesh. None of it depends on the solution: :class:`Lookahead` does it in a thread beside the launch, and the
driver takes the answers afterwards: :func:`wendel.remesh.transfer.locate` keeps its recent answers by the
bytes of mesh and points, so the driver's own calls with the same arrays get the thread's arrays, bit for bit
what they would have computed. The thread only reads (gmsh stays in the driver's main thread or the worker);
the driver joins it before it goes on (:meth:`Lookahead.join`), so nothing is computed twice or concurrently.
``WENDEL_LOOKAHEAD=0``: no thread (every answer computed when asked, as before).
"""

from __future__ import annotations

import os
import threading
from pathlib import Path


class Lookahead:
    """One thread per launch: :meth:`start` beside the launch, :meth:`join` before the driver goes on; the
    next mesh (:meth:`mesh`) and its quality (:meth:`quality`) by path."""

    def __init__(self):
        self.thread: threading.Thread | None = None
        self.meshes: dict[str, dict] = {}
        self.qualities: dict[str, dict] = {}
        self.seconds = 0.0                 # spent in the threads (beside the launches; the mesh worker's wait in it)
        self.waited = 0.0                  # the driver's wait for them after the launches
        self.taken = 0                     # next meshes taken from the worker and read here
        self._booked = 0.0

    def start(self, proc, k: int) -> None:
        """Beside the launch that ends before step ``k`` (0-based index into ``proc.steps``; the cooling when
        ``k`` is past them): the current mesh is ``proc.mesh``."""
        self.join()
        if os.environ.get("WENDEL_LOOKAHEAD", "1") == "0" or getattr(proc, "mesh", None) is None:
            return
        self.thread = threading.Thread(target=self._run, args=(proc, k), daemon=True, name="wendel-lookahead")
        self.thread.start()

    def join(self) -> None:
        if self.thread is not None:
            import time

            t0 = time.perf_counter()
            self.thread.join()
            self.waited += time.perf_counter() - t0
            self.thread = None

    def unbooked(self) -> float:
        """The driver's wait since the last call (the remesh report books it: mostly the mesh worker's gmsh)."""
        booked, self._booked = self._booked, self.waited
        return self.waited - booked

    def mesh(self, path: Path) -> dict | None:
        self.join()
        return self.meshes.pop(str(path), None)

    def quality(self, path: Path) -> dict | None:
        return self.qualities.pop(str(path), None)

    def _run(self, proc, k: int) -> None:
        import time

        from ..remesh import mesher, quality, transfer
        from ..remesh.removal import quadrature_points
        from ..remesh.step import _targets

        t0 = time.perf_counter()
        try:
            cur = proc.mesh
            pts, cells = cur["points"], cur["cells"]
            if proc.block.probes:
                transfer.locate(pts, cells, proc.probe_positions())
            steps = proc.steps
            if not (1 <= k < len(steps)) or steps[k].depth == steps[k - 1].depth:
                return                                     # the cooling next, or a dwell: no new body
            slice_points, _ = proc.slice_quadrature(steps[k - 1].depth, steps[k].depth)
            if len(slice_points):
                transfer.locate(pts, cells, slice_points)
            path = proc.files.root / f"meshes/step-{k + 1:03d}.msh"
            if not proc.builder.take(path):                # not built ahead: the driver meshes it (gmsh)
                return
            p, _, c, _, facets, tags = mesher.read_mesh(path)
            new = {"points": p, "cells": c, "facets": facets, "tags": tags}
            self.meshes[str(path)] = new
            self.taken += 1
            dim = proc.dim
            transfer.locate(pts, cells, _targets(path, p[:, :dim], c, dim))
            if proc.block.transfer == "conservative" and not transfer._same_mesh(pts, cells, p, c):
                transfer.locate(pts, cells, quadrature_points(p, c))
            self.qualities[str(path)] = quality.mesh_quality(p, c)
        except Exception:               # anything not found here is found by the driver when it asks
            pass
        finally:
            self.seconds += time.perf_counter() - t0

