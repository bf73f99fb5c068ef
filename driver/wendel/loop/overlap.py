"""Driver work done while FreeFEM solves, off the run's critical path (issue 20).

- :class:`Behind`: accepts the increments FreeFEM has committed (VTU, mesh quality, histories, checkpoint:
  :func:`wendel.loop.quasistatic.accept`) in a thread while the launch goes on, so that a launch of many
  increments leaves only its last increment's files to the driver when FreeFEM ends. The same function
  runs after the launch as before and takes what is left; only one of the two runs at a time (the thread
  is stopped and joined first). An error of the thread is raised when the launch ends, and the caller
  then does not accept further (as when its own accept raised it).
- :func:`preload`: imports the remeshing packages (scipy, gmsh) in a thread while FreeFEM solves the first
  segment of a remeshing run, instead of at its first remesh.
- :func:`mesh_of`: the points and cells of a mesh file read once per run process (a remeshing run reads
  each segment's mesh after every launch, and the quality judge and the VTU both need it).
"""

from __future__ import annotations

import importlib
import os
import threading
import time
from pathlib import Path

from ..results import vtu

POLL = 0.2
"""s between two looks for a committed increment."""


class Behind:
    """``with Behind(work, state):`` calls ``work()`` every :data:`POLL` seconds in a thread until the block
    ends. The seconds ``work`` takes there are moved from ``state.post_seconds`` (the driver's output on
    the critical path) to ``state.behind_seconds``. ``ended``: when the block ended (FreeFEM's launch
    ended), ``waited``: how long the block's end waited for the thread's current call to finish.
    ``enabled = False``: no thread (FreeFEM's ranks take every core: the work would only slow them down)."""

    def __init__(self, work, state, enabled: bool = True):
        self.work, self.state, self.enabled = work, state, enabled
        self.stop = threading.Event()
        self.ended: float | None = None
        self.waited = 0.0
        self.error: BaseException | None = None

    def __enter__(self):
        self.thread = threading.Thread(target=self._loop, daemon=True, name="wendel-accept")
        if self.enabled:
            self.thread.start()
        return self

    def _loop(self):
        while not self.stop.wait(POLL):
            before = self.state.post_seconds
            try:
                self.work()
            except Exception as exc:        # raised by the block's end; the caller must not call work again
                self.error = exc
                return
            finally:
                self.state.behind_seconds += self.state.post_seconds - before
                self.state.post_seconds = before

    def __exit__(self, *exc):
        self.ended = time.perf_counter()
        self.stop.set()
        interrupted = False
        while self.thread.is_alive():       # never leave the thread working beside the caller's accept
            try:
                self.thread.join()
            except KeyboardInterrupt:
                interrupted = True
        self.waited = time.perf_counter() - self.ended
        if interrupted:                     # an interrupt outranks the block's own error (a step to cut)
            raise KeyboardInterrupt
        if self.error is not None and exc[0] is None:
            raise self.error             # as if the accept after the launch had raised it
        return False


_PRELOADED: set[str] = set()


def preload(*modules: str) -> None:
    """Import ``modules`` in a daemon thread (once per process); a later import waits for it if needed."""
    todo = [m for m in modules if m not in _PRELOADED]
    if not todo or os.environ.get("WENDEL_NO_PRELOAD"):
        return
    _PRELOADED.update(todo)

    def _import():
        for m in todo:
            try:
                importlib.import_module(m)
            except Exception:            # the import where it is needed reports it
                return

    threading.Thread(target=_import, daemon=True, name="wendel-preload").start()


_MESHES: dict[tuple, tuple] = {}


def mesh_of(path: Path, dimension: int):
    """``vtu.read_mesh(path, dimension)``, read again only when the file changed (size or time)."""
    st = os.stat(path)
    key = (str(Path(path).resolve()), dimension, st.st_size, st.st_mtime_ns, st.st_ino)
    if key not in _MESHES:
        if len(_MESHES) > 8:
            _MESHES.clear()
        points, cells = vtu.read_mesh(path, dimension)
        points.setflags(write=False)         # shared by every caller: nobody may change it
        cells.setflags(write=False)
        _MESHES[key] = points, cells
    return _MESHES[key]
