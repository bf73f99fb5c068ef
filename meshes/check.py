"""Check a mesh file before FreeFEM reads it: the version FreeFEM's ``gmshload`` understands, complete
sections, finite coordinates, elements of positive size, and the physical tags (named boundaries).

FreeFEM reads gmsh's ASCII MSH 2.2 only (4.1 exits in 2D and crashes in 3D): any other file is refused
with its version and the command that converts it.

>>> import tempfile, pathlib
>>> p = pathlib.Path(tempfile.mkdtemp()) / "m.msh"
>>> _ = p.write_text("$MeshFormat\\n4.1 0 8\\n$EndMeshFormat\\n")
>>> inspect_file(p)
Traceback (most recent call last):
...
ValueError: ... is a gmsh MSH 4.1 file; FreeFEM reads MSH 2.2 only: convert it with `gmsh ... -0 -format msh22 -o ...`
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

# gmsh element types: (dimension, nodes) of the linear and quadratic simplices wendel uses
ELEMENT_TYPES = {1: (1, 2), 2: (2, 3), 4: (3, 4), 8: (1, 3), 9: (2, 6), 11: (3, 10), 15: (0, 1)}


@dataclass
class MeshInfo:
    """What a mesh file holds."""

    path: Path
    dimension: int
    nodes: int
    elements: int
    tags: dict[int, set[int]] = field(default_factory=dict)    # dimension -> physical tags present
    names: dict[int, str] = field(default_factory=dict)        # physical tag -> name ($PhysicalNames)


def _sections(text: str, path: Path) -> dict[str, list[str]]:
    out, name, body = {}, None, []
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("$End"):
            if name is None or s[4:] != name:
                raise ValueError(f"{path}: malformed mesh file: {s} without ${s[4:]}")
            out[name], name, body = body, None, []
        elif s.startswith("$") and name is None:
            name, body = s[1:], []
        elif name is not None:
            body.append(s)
    if name is not None:
        raise ValueError(f"{path}: truncated mesh file: section ${name} has no $End{name}")
    return out


def inspect_file(path: str | Path) -> MeshInfo:
    """Read and check the MSH 2.2 file ``path``; ValueError names the file and what is wrong."""
    import numpy as np      # here: `wendel check` of a builder scene does not pay for it

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such mesh file")
    raw = path.read_bytes()
    if not raw.lstrip().startswith(b"$MeshFormat"):
        raise ValueError(f"{path}: not a gmsh mesh file (no $MeshFormat header); wendel reads gmsh MSH 2.2")
    head = raw.split(b"\n", 3)
    fmt = head[1].split() if len(head) > 1 else []
    version = fmt[0].decode(errors="replace") if fmt else "?"
    convert = f"convert it with `gmsh {path} -0 -format msh22 -o {path.with_suffix('')}-22.msh`"
    if not version.startswith("2."):
        raise ValueError(f"{path} is a gmsh MSH {version} file; FreeFEM reads MSH 2.2 only: {convert}")
    if len(fmt) > 1 and fmt[1] != b"0":
        raise ValueError(f"{path} is a binary MSH {version} file; FreeFEM reads ASCII only: {convert}")
    try:
        text = raw.decode()
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not an ASCII mesh file") from None
    sec = _sections(text, path)
    for needed in ("Nodes", "Elements"):
        if needed not in sec:
            raise ValueError(f"{path}: truncated mesh file: no ${needed} section")
    try:
        n = int(sec["Nodes"][0])
        rows = [r.split() for r in sec["Nodes"][1:1 + n]]
        if len(rows) != n or any(len(r) != 4 for r in rows):
            raise ValueError
        ids = np.array([int(r[0]) for r in rows])
        xyz = np.array([[float(v) for v in r[1:]] for r in rows])
    except (ValueError, IndexError):
        raise ValueError(f"{path}: truncated or malformed $Nodes section") from None
    if not np.isfinite(xyz).all():
        bad = int(ids[~np.isfinite(xyz).all(axis=1)][0])
        raise ValueError(f"{path}: node {bad} has a non-finite coordinate")
    index = {int(i): k for k, i in enumerate(ids)}
    info = MeshInfo(path, 0, n, 0)
    for line in sec.get("PhysicalNames", [])[1:]:
        parts = line.split(maxsplit=2)
        if len(parts) == 3:
            info.names[int(parts[1])] = parts[2].strip('"')
    cells: dict[int, list[list[int]]] = {}
    try:
        m = int(sec["Elements"][0])
        rows = sec["Elements"][1:1 + m]
        if len(rows) != m:
            raise ValueError
        for r in rows:
            v = [int(x) for x in r.split()]
            etype, ntags = v[1], v[2]
            if etype not in ELEMENT_TYPES:
                raise ValueError(f"{path}: element {v[0]} has gmsh type {etype}; wendel meshes hold simplices "
                                 f"(lines, triangles, tetrahedra)")
            dim, nn = ELEMENT_TYPES[etype]
            conn = v[3 + ntags:]
            if len(conn) != nn:
                raise ValueError
            physical = v[3] if ntags > 0 else 0
            info.tags.setdefault(dim, set()).add(physical)
            cells.setdefault(dim, []).append([index[c] for c in conn[:dim + 1]])
    except KeyError as exc:
        raise ValueError(f"{path}: an element names node {exc.args[0]}, which $Nodes does not hold") from None
    except ValueError as exc:
        if str(exc).startswith(str(path)):
            raise
        raise ValueError(f"{path}: truncated or malformed $Elements section") from None
    info.dimension = max(d for d in cells if d in (2, 3)) if any(d in (2, 3) for d in cells) else 0
    if info.dimension == 0:
        raise ValueError(f"{path}: no triangles or tetrahedra")
    if info.dimension == 2 and np.ptp(xyz[:, 2]) > 0:
        raise ValueError(f"{path}: a mesh of triangles must lie in the plane z = constant")
    body = np.array(cells[info.dimension])
    info.elements = len(body)
    if info.tags.get(info.dimension, {0}) == {0} or info.tags.get(info.dimension - 1, {0}) == {0}:
        raise ValueError(f"{path}: no physical tags on the {'surfaces' if info.dimension == 3 else 'curves'} "
                         f"or on the body: boundaries must be named by physical groups (meshes/labels.py)")
    p = xyz[:, :info.dimension]
    e = p[body[:, 1:]] - p[body[:, :1]]
    size = np.linalg.det(e)
    scale = np.ptp(p, axis=0).max() ** info.dimension
    if (size <= 1e-14 * scale).any():
        k = int(np.argmax(size <= 1e-14 * scale))
        what = "inverted" if size[k] < 0 else "degenerate (zero size)"
        raise ValueError(f"{path}: {int((size <= 1e-14 * scale).sum())} {what} or degenerate elements "
                         f"(the first is body element {k + 1})")
    return info
