"""A 3D tool given as an STL surface: read (ASCII or binary), validate, and write the triangle table that
edp/plugins/wendel_tool.cpp measures signed distances on (numbers only).

Validated: the file exists and is an STL file, every coordinate is finite, no triangle is degenerate, and the
surface is closed and consistently oriented (after merging equal vertices every edge belongs to exactly two
triangles that run along it in opposite directions), so that inside and outside are defined. A surface
whose normals point inwards (negative enclosed volume) is turned around. Errors are ValueErrors that name
the file; the scene check adds the key.

>>> import numpy as np
>>> tris = np.array([[[0, 0, 0], [0, 1, 0], [1, 0, 0]], [[0, 0, 0], [1, 0, 0], [0, 0, 1]],
...                  [[0, 0, 0], [0, 0, 1], [0, 1, 0]], [[1, 0, 0], [0, 1, 0], [0, 0, 1]]], float)
>>> t = table(tris, "tet")
>>> t.shape, round(float(t[3, 9:12] @ [1, 1, 1]) ** 2, 12)      # the slanted face's normal points out
((4, 34), 3.0)
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

MAX_TRIANGLES = 2_000_000


def read(path: Path) -> np.ndarray:
    """The triangles (n, 3, 3) of the STL file ``path``; ValueError naming the file if it cannot be read."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such STL file")
    data = path.read_bytes()
    if len(data) >= 84:
        (n,) = struct.unpack_from("<I", data, 80)
        if len(data) == 84 + 50 * n and n > 0:                     # binary: 80-byte header, count, 50 bytes each
            if n > MAX_TRIANGLES:
                raise ValueError(f"{path}: {n} triangles, more than {MAX_TRIANGLES}")
            rec = np.frombuffer(data, dtype=np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")]),
                                count=n, offset=84)
            return rec["v"].astype(float)
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        raise ValueError(f"{path}: neither a binary STL (size 84 + 50 x count bytes) nor ASCII STL text") from None
    if not text.lstrip().lower().startswith("solid"):
        raise ValueError(f"{path}: not an STL file (ASCII STL starts with 'solid')")
    rows = []
    for k, line in enumerate(text.splitlines(), 1):
        words = line.split()
        if words and words[0].lower() == "vertex":
            try:
                if len(words) != 4:
                    raise ValueError
                rows.append([float(w) for w in words[1:]])
            except ValueError:
                raise ValueError(f"{path}, line {k}: 'vertex x y z' with three numbers expected") from None
    if not rows or len(rows) % 3:
        raise ValueError(f"{path}: {len(rows)} vertices, not a positive multiple of 3 (3 per facet)")
    if len(rows) > 3 * MAX_TRIANGLES:
        raise ValueError(f"{path}: more than {MAX_TRIANGLES} triangles")
    return np.asarray(rows, float).reshape(-1, 3, 3)


def table(tris: np.ndarray, name: str) -> np.ndarray:
    """The 34 numbers per triangle of wendel_tool.cpp (vertices, face normal, edge and vertex pseudo-normals,
    bounding sphere) of a closed surface; ValueError naming ``name`` if it is not one."""
    if not np.isfinite(tris).all():
        raise ValueError(f"{name}: coordinates that are not finite numbers")
    if np.abs(tris).max() > 1e12:
        raise ValueError(f"{name}: coordinates beyond 1e12 m")
    pts, idx = np.unique(tris.reshape(-1, 3), axis=0, return_inverse=True)
    f = idx.reshape(-1, 3)
    if (f[:, 0] == f[:, 1]).any() or (f[:, 1] == f[:, 2]).any() or (f[:, 2] == f[:, 0]).any():
        raise ValueError(f"{name}: a triangle with a repeated vertex")
    a, b, c = pts[f[:, 0]], pts[f[:, 1]], pts[f[:, 2]]
    cross = np.cross(b - a, c - a)
    area2 = np.linalg.norm(cross, axis=1)
    scale = np.ptp(pts, axis=0).max()
    if (area2 <= 1e-14 * scale ** 2).any():
        raise ValueError(f"{name}: {(area2 <= 1e-14 * scale ** 2).sum()} degenerate (zero-area) triangles")
    # closed and consistently oriented: each directed edge once, and its reverse once
    nv = len(pts)
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    key = directed[:, 0] * nv + directed[:, 1]
    uniq, count = np.unique(key, return_counts=True)
    if (count > 1).any():
        raise ValueError(f"{name}: an edge is run twice in the same direction (inconsistent orientation or "
                         f"more than two triangles at an edge)")
    reverse = directed[:, 1] * nv + directed[:, 0]
    if not np.isin(reverse, uniq).all():
        open_edges = (~np.isin(reverse, uniq)).sum()
        raise ValueError(f"{name}: not a closed surface ({open_edges} edges belong to one triangle only)")
    volume = np.einsum("ij,ij->", a, cross) / 6.0
    if volume < 0:                                          # inward normals: turn the surface around
        f = f[:, [0, 2, 1]]
        return table(pts[f], name)
    normal = cross / area2[:, None]
    # angle-weighted vertex pseudo-normals, edge pseudo-normals (sum of the two face normals)
    vn = np.zeros_like(pts)
    corner = pts[f]
    for k in range(3):
        p, q, r = corner[:, k], corner[:, (k + 1) % 3], corner[:, (k + 2) % 3]
        e1, e2 = q - p, r - p
        cosang = np.einsum("ij,ij->i", e1, e2) / (np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1))
        np.add.at(vn, f[:, k], np.arccos(np.clip(cosang, -1, 1))[:, None] * normal)
    vn /= np.linalg.norm(vn, axis=1)[:, None]
    order = np.argsort(key)                                # directed edge -> its triangle
    en = np.empty((len(f), 3, 3))
    for k in range(3):
        rev = f[:, (k + 1) % 3] * nv + f[:, k]
        other = order[np.searchsorted(key[order], rev)] % len(f)
        s = normal + normal[other]
        en[:, k] = s / np.linalg.norm(s, axis=1)[:, None]
    centre = (a + b + c) / 3.0
    radius = np.max([np.linalg.norm(v - centre, axis=1) for v in (a, b, c)], axis=0) * (1 + 1e-12)
    out = np.concatenate([a, b, c, normal, en.reshape(-1, 9), vn[f].reshape(-1, 9), centre, radius[:, None]], axis=1)
    return out


def write_table(stl: Path, out: Path) -> Path:
    """Read and validate ``stl``, write its triangle table to ``out`` (count, then 34 numbers a row)."""
    t = table(read(stl), str(stl))
    with open(out, "w") as fh:
        fh.write(f"{len(t)}\n")
        np.savetxt(fh, t, fmt="%.17g")
    return out


def sphere(path: Path, radius: float = 1.0, centre=(0.0, 0.0, 1.0), fine: float = 0.01, coarse: float = 0.25,
           zone: float = 0.15) -> Path:
    """Write a binary STL of a sphere meshed by gmsh, its triangles ``fine`` (m) within ``zone`` of the pole
    below the centre (where a ball pressed along -z touches), growing to ``coarse`` away from it: a test and
    demonstration tool (workflows/tools/sphere-r1.stl)."""
    import gmsh

    cx, cy, cz = centre
    gmsh.initialize(["-noenv"], readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Verbosity", 0)
        gmsh.model.add("sphere")
        gmsh.model.occ.addSphere(cx, cy, cz, radius)
        gmsh.model.occ.synchronize()
        f = gmsh.model.mesh.field.add("MathEval")
        r = f"Sqrt((x - {cx!r})^2 + (y - {cy!r})^2 + (z - {cz - radius!r})^2)"
        gmsh.model.mesh.field.setString(f, "F", f"Min({coarse!r}, {fine!r} + 0.5 * Max(0, {r} - {zone!r}))")
        gmsh.model.mesh.field.setAsBackgroundMesh(f)
        for k in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
            gmsh.option.setNumber(f"Mesh.{k}", 0)
        gmsh.option.setNumber("Mesh.Binary", 1)
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return Path(path)
