"""A mesh file read once per process while it stays unchanged (issue 20).

A drilling run reads each removal step's mesh five times (the builder's check, the transfer's old and new
mesh, the boundary facets, the driver's accept) and meshio parses MSH 2.2 text in Python loops: 3.2 s of
drilling-deep-rz's 41 s (cProfile, 247 reads of 50 meshes). :func:`read` keeps the last few parsed files,
keyed by path, size, modification time and inode: a file written again is read again. The mesh returned is
shared by every caller: read from it, copy what you change (:func:`wendel.results.vtu.read_mesh` and
:func:`wendel.remesh.mesher.read_mesh` return copies).

gmsh's ASCII MSH 2.2 with only the sections wendel's meshes have (PhysicalNames, Nodes, Elements with two tags)
is parsed with numpy (:func:`read_msh22`): 0.22 s against meshio's 0.84-1.38 s for the step-42 ball at 217k
tetrahedra, the driver's accept after the last FreeFEM increment on every run; the same Mesh as meshio's (test).
Anything else goes to meshio.
"""

from __future__ import annotations

import os
import re
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
    m = (read_msh22(path) if file_format == "gmsh" else None) or meshio.read(path, file_format=file_format)
    with _LOCK:
        _CACHE[key] = m
        while len(_CACHE) > KEEP:
            _CACHE.popitem(last=False)
    return m


_SECTION = re.compile(rb"^\$(\w+)\s*$", re.M)


def read_msh22(path):
    """The meshio.Mesh of an ASCII MSH 2.2 file whose sections are MeshFormat, PhysicalNames, Nodes and
    Elements, each element with two tags (physical, elementary); None for any other file (meshio reads it).
    Elements of one type in a row are one cell block, as meshio makes them."""
    import numpy as np
    import meshio
    from meshio._common import num_nodes_per_cell
    from meshio.gmsh.common import _gmsh_to_meshio_order, _gmsh_to_meshio_type

    data = open(path, "rb").read()
    marks = list(_SECTION.finditer(data))
    names = [m.group(1).decode() for m in marks]
    if names[:2] != ["MeshFormat", "EndMeshFormat"]:
        return None
    sections = {}
    for a, b in zip(marks[0::2], marks[1::2]):
        if b.group(1).decode() != "End" + a.group(1).decode():
            return None
        sections[a.group(1).decode()] = data[a.end():b.start()]
    if len(marks) % 2 or set(sections) - {"MeshFormat", "PhysicalNames", "Nodes", "Elements"} \
            or not {"Nodes", "Elements"} <= set(sections):
        return None
    head = sections["MeshFormat"].split()
    if len(head) != 3 or head[0].split(b".")[0] != b"2" or head[1] != b"0":
        return None                                    # MSH 2 ASCII only
    field_data = {}
    if "PhysicalNames" in sections:
        lines = sections["PhysicalNames"].strip().splitlines()
        for line in lines[1:int(lines[0]) + 1]:
            dim, tag, name = line.split(maxsplit=2)
            name = name.strip()
            if not (name.startswith(b'"') and name.endswith(b'"')) or b'"' in name[1:-1]:
                return None
            field_data[name[1:-1].decode()] = np.array([int(tag), int(dim)])
    nodes = sections["Nodes"]
    n_text, _, rest = nodes.lstrip().partition(b"\n")
    n = int(n_text)
    table = _numbers(rest, float)
    if table is None or table.size != 4 * n:
        return None
    table = table.reshape(n, 4)
    points = np.ascontiguousarray(table[:, 1:])
    node_tags = table[:, 0].astype(np.int32) - 1
    remap = -np.ones(node_tags.max() + 1, dtype=np.int32)
    remap[node_tags] = np.arange(n, dtype=np.int32)
    m_text, _, rest = sections["Elements"].lstrip().partition(b"\n")
    m = int(m_text)
    tokens = _numbers(rest, np.int64)
    if tokens is None:
        return None
    cells, physical, geometrical = [], [], []
    p, count = 0, 0
    while p < tokens.size:
        # a run of elements of one type: rows of equal length, cut at the first row of another type
        if p + 3 > tokens.size or tokens[p + 2] != 2 or int(tokens[p + 1]) not in _gmsh_to_meshio_type:
            return None
        kind = int(tokens[p + 1])
        cell_type = _gmsh_to_meshio_type[kind]
        width = 5 + num_nodes_per_cell[cell_type]
        rows = tokens[p:p + (tokens.size - p) // width * width].reshape(-1, width)
        other = np.flatnonzero((rows[:, 1] != kind) | (rows[:, 2] != 2))
        rows = rows[:other[0]] if other.size else rows      # (all full rows alike: the next type starts after)
        nodes = rows[:, 5:] - 1
        if not len(rows) or nodes.min() < 0 or nodes.max() >= remap.size or (remap[nodes] < 0).any():
            return None                                       # a truncated row or an unknown node
        cells.append((cell_type, _gmsh_to_meshio_order(cell_type, remap[nodes])))
        physical.append(rows[:, 3].astype(np.int32))
        geometrical.append(rows[:, 4].astype(np.int32))
        p += rows.size
        count += len(rows)
    if count != m:
        return None
    return meshio.Mesh(points, cells, cell_data={"gmsh:physical": physical, "gmsh:geometrical": geometrical},
                       field_data=field_data)


def _numbers(text: bytes, dtype):
    """The whitespace-separated numbers of ``text`` (numpy's C parser, 3x faster than split and convert),
    or None when some token is not a number of that type."""
    import warnings

    import numpy as np

    with warnings.catch_warnings():
        warnings.simplefilter("error")        # a token it cannot read: a warning and a truncated array
        try:
            return np.fromstring(text, dtype=dtype, sep=" ")
        except (ValueError, DeprecationWarning):
            return None
