"""FreeFEM's field files to ParaView: one VTU per increment, a PVD index (pictures: :mod:`.pictures`).

FreeFEM writes nodal fields (``name.node.txt``, P1 values in the node order of the mesh file,
components interleaved) and cell fields (``name.cell.txt``, binary: :func:`read_array`); this module
turns them into VTU with meshio, in float64, with 2D vectors padded to 3 components so ParaView can warp
by them.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

CELL_TYPES = {2: "triangle", 3: "tetra"}


def read_array(path: Path) -> np.ndarray:
    r"""Read edp's array formats: text (the count, then the values, any whitespace) or binary (FreeFEM's
    BinaryIO ``SaveVec``, cell fields: the count as a little-endian int64, then float64 values).

    >>> import tempfile; d = Path(tempfile.mkdtemp())
    >>> _ = (d / "t.txt").write_text("2\t\n\t0.5\t-1e-300\t")
    >>> _ = (d / "b.txt").write_bytes((2).to_bytes(8, "little") + np.array([0.5, -1e-300]).tobytes())
    >>> read_array(d / "t.txt").tolist() == read_array(d / "b.txt").tolist() == [0.5, -1e-300]
    True
    """
    with open(path, "rb") as f:
        raw = f.read()
    if _binary(raw):
        n = int.from_bytes(raw[:8], "little")
        if len(raw) != 8 + 8 * n:
            raise ValueError(f"{path}: header says {n} values, found {(len(raw) - 8) / 8:g} (binary)")
        return np.frombuffer(raw, dtype="<f8", offset=8, count=n).astype(float)
    data = np.array(raw.split(), dtype=float)
    if data.size == 0:
        raise ValueError(f"{path}: empty array file")
    n = int(data[0])
    if data.size - 1 != n:
        raise ValueError(f"{path}: header says {n} values, found {data.size - 1}")
    return data[1:]


def _binary(raw: bytes) -> bool:
    """Whether an array file is binary: its int64 count has a zero high byte (below 2^56 values), a NUL that
    text never holds."""
    return len(raw) >= 8 and raw[7] == 0


def complete_array(path: Path) -> bool:
    r"""Whether the array file ``path`` holds all the values its count announces, i.e. it was not cut short
    by a crash or a full disk.

    FreeFEM writes ``n``, then rows of 5 values, the last one ending with a tab: checked by counting rows
    and the last row's values (no parsing of the rest); another layout is parsed whole.

    >>> import tempfile; p = Path(tempfile.mkdtemp()) / "a.txt"
    >>> _ = p.write_text("7\t\n\t1\t2\t3\t4\t5\n\t6\t7\t")
    >>> complete_array(p), (p.write_text("7\t\n\t1\t2\t3\t4\t5\n\t6\t7") and complete_array(p))
    (True, False)
    """
    try:
        data = path.read_bytes()
        if _binary(data):
            return len(data) == 8 + 8 * int.from_bytes(data[:8], "little")
        head, _, body = data.partition(b"\n")
        n = int(head)
        rows = -(-n // 5)
        last = body[body.rfind(b"\n") + 1:]
        if data.endswith(b"\t") and body.count(b"\n") == rows - 1 and len(last.split()) == n - 5 * (rows - 1):
            return True
        if data.endswith(b"\t") or b"\t" not in body:
            return read_array(path).size == n         # another layout (one value per line): parse it
        return False
    except (OSError, ValueError):
        return False


def write_array(path: Path, values) -> None:
    """Write an array as FreeFEM's BinaryIO ``SaveVec`` does (the count as a little-endian int64, then float64
    values): what edp's ``readArray`` and :func:`read_array` read, the same values as the 17-digit text this
    wrote before, without formatting them (drilling-3d: 0.3 s of text for 56 state files; issue 20)."""
    v = np.ascontiguousarray(np.asarray(values, dtype=float).ravel(), dtype="<f8")
    with open(path, "wb") as f:
        f.write(v.size.to_bytes(8, "little"))
        f.write(v.tobytes())


def read_mesh(path: Path, dimension: int) -> tuple[np.ndarray, np.ndarray]:
    """Points (n, 3) and the cells of the given dimension of a gmsh file."""
    from . import meshfile      # meshio is imported there, off a run's critical path (wendel.loop.overlap.preload)
    m = meshfile.read(path, "gmsh")         # parsed once while the file stays unchanged: copies below
    cells = np.concatenate([b.data for b in m.cells if b.type == CELL_TYPES[dimension]])
    return m.points.copy(), cells


def read_vertices(vertices_txt: Path) -> np.ndarray:
    """FreeFEM's vertex coordinates (n, 3) from ``vertices.txt`` (component-major: all x, all y, all z)."""
    return read_array(vertices_txt).reshape(3, -1).T


def check_node_order(vertices_txt: Path, points: np.ndarray) -> None:
    """Fail loudly if FreeFEM's vertex order differs from the mesh file's node order."""
    xyz = read_vertices(vertices_txt)
    n = len(xyz)
    if n != len(points) or not np.allclose(xyz, points[:, :3], rtol=0, atol=1e-9 * max(1.0, np.abs(points).max())):
        raise RuntimeError(f"{vertices_txt}: FreeFEM's vertices do not match the nodes of the mesh file "
                           f"({n} vs {len(points)}); the VTU would be wrong")


def _per_entity(f: Path, suffix: str, n: int, what: str) -> tuple[str, np.ndarray, int]:
    """The array of ``f`` (``NAME.node.txt`` / ``NAME.cell.txt``) as (name, values, components)."""
    v = read_array(f)
    if v.size % n:
        raise ValueError(f"{f}: {v.size} values do not fit {n} {what}")
    ncomp = v.size // n
    return f.name.removesuffix(suffix), (v.reshape(n, ncomp) if ncomp > 1 else v), ncomp


def increment_fields(inc_dir: Path, n_points: int, n_cells: int, dimension: int):
    """Point and cell data of one increment folder, shaped for meshio."""
    point_data, cell_data = {}, {}
    for f in sorted(inc_dir.glob("*.node.txt")):
        name, v, ncomp = _per_entity(f, ".node.txt", n_points, "nodes")
        if ncomp == 2 and dimension == 2:
            v = np.column_stack([v, np.zeros(n_points)])
        point_data[name] = v
    for f in sorted(inc_dir.glob("*.cell.txt")):
        name, v, _ = _per_entity(f, ".cell.txt", n_cells, "cells")
        cell_data[name] = [v]
    return point_data, cell_data


def current_points(point_data: dict, points: np.ndarray) -> np.ndarray:
    """Points at the current positions of an updated-Lagrangian increment (its ``position`` field).

    >>> current_points({"position": np.array([[1.0, 2.0, 0.0]])}, np.zeros((1, 3)))
    array([[1., 2., 0.]])
    """
    pos = np.asarray(point_data.pop("position"), dtype=float)
    if pos.shape != (len(points), 3):
        raise ValueError(f"position field of shape {pos.shape} does not fit {len(points)} points")
    return pos


ZLIB_LEVEL = 1
"""The VTU blocks' zlib level: meshio compresses at zlib's default (6), the slowest part of writing a VTU; level 1
takes about 0.6x its time for 1 % more bytes on float64 fields (drilling-3d: 20 against 33 ms a file, issue 20).
The files stay ``vtkZLibDataCompressor`` VTU: any reader reads them as before."""


class _Zlib:
    """zlib for meshio's VTU writer: ``compress`` at :data:`ZLIB_LEVEL`, all else zlib's own."""

    def compress(self, data, level=None):
        import zlib

        return zlib.compress(data, ZLIB_LEVEL if level is None else level)

    def __getattr__(self, name):
        import zlib

        return getattr(zlib, name)


def _meshio():
    """meshio, its VTU writer compressing at :data:`ZLIB_LEVEL` (a meshio without the module-level zlib it
    looks up when it writes keeps its own)."""
    import meshio
    from meshio.vtu import _vtu

    if getattr(_vtu, "zlib", None) is not None and not isinstance(_vtu.zlib, _Zlib):
        _vtu.zlib = _Zlib()
    return meshio


def write_vtu(path: Path, points, cells, dimension: int, point_data, cell_data) -> None:
    """Write one VTU (atomic: written beside, then renamed; zlib at :data:`ZLIB_LEVEL`)."""
    meshio = _meshio()
    mesh = meshio.Mesh(points, [(CELL_TYPES[dimension], cells)], point_data=point_data, cell_data=cell_data)
    tmp = path.with_suffix(".tmp.vtu")
    meshio.write(tmp, mesh, binary=True)
    os.replace(tmp, path)


def write_pvd(path: Path, entries: list[tuple[float, str]]) -> None:
    """A ParaView collection: (time = load factor, relative VTU path) per increment."""
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    coll = ET.SubElement(root, "Collection")
    for t, f in entries:
        ET.SubElement(coll, "DataSet", timestep=repr(float(t)), group="", part="0", file=f)
    tmp = path.with_suffix(".tmp")
    ET.ElementTree(root).write(tmp, xml_declaration=True, encoding="utf-8")
    os.replace(tmp, path)


def read_pvd(path: Path) -> list[tuple[float, Path]]:
    """The (time, VTU path) entries of a PVD file."""
    root = ET.parse(path).getroot()
    return [(float(d.get("timestep")), path.parent / d.get("file")) for d in root.iter("DataSet")]


def write_increment(path: Path, mesh: Path, inc_dir: Path, dimension: int, updated_lagrangian: bool = False) -> None:
    """The VTU at ``path`` of an accepted increment: its mesh file ``mesh``, its FreeFEM folder ``inc_dir``
    (updated-Lagrangian: the VTU is the deformed body itself, its points the current positions)."""
    points, cells = read_mesh(mesh, dimension)
    pdata, cdata = increment_fields(inc_dir, len(points), len(cells), dimension)
    if updated_lagrangian:
        points = current_points(pdata, points)
    write_vtu(path, points, cells, dimension, pdata, cdata)
