"""A mesh file read once per process while it stays unchanged (issue 20).

A drilling run reads each removal step's mesh five times (the builder's check, the transfer's old and new
mesh, the boundary facets, the driver's accept) and meshio parses MSH 2.2 text in Python loops: 3.2 s of
drilling-deep-rz's 41 s (cProfile, 247 reads of 50 meshes). :func:`read` keeps the last few parsed files,
keyed by path, size, modification time and inode: a file written again is read again. The mesh returned is
shared by every caller: read from it, copy what you change (:func:`wendel.results.vtu.read_mesh` and
:func:`wendel.remesh.mesher.read_mesh` return copies).
"""

from __future__ import annotations

import os
import threading
from collections import OrderedDict
from pathlib import Path

KEEP = 6
"""Parsed files kept (a remeshing step needs the old and the new mesh)."""

_CACHE: OrderedDict = OrderedDict()
_LOCK = threading.Lock()        # the accept may run in a thread beside the driver (wendel.loop.overlap.Behind)


def read(path, file_format: str | None = None):
    """``meshio.read(path, file_format)``, parsed again only when the file changed."""
    import meshio       # here: its import (0.2 s) is off a run's critical path (wendel.loop.overlap.preload)
    if file_format is None and str(path).endswith(".msh"):
        file_format = "gmsh"             # what meshio infers from the name: one entry for both spellings
    st = os.stat(path)
    key = (str(Path(path).resolve()), file_format, st.st_size, st.st_mtime_ns, st.st_ino)
    with _LOCK:
        if key in _CACHE:
            _CACHE.move_to_end(key)
            return _CACHE[key]
    m = meshio.read(path, file_format=file_format)
    with _LOCK:
        _CACHE[key] = m
        while len(_CACHE) > KEEP:
            _CACHE.popitem(last=False)
    return m
