"""The mesh of a separated DG body: cut along its opened faces, which become the named boundary ``opened``.

dg.idp writes the midpoints of the faces opened so far (``dg_open_faces.txt``, x and y per face) with every
accepted increment of a separating 2D run. :func:`split` duplicates the vertices along those faces, so the two
sides of an opened face no longer share it, and :func:`write_separated` writes the result as ``separated.msh``
(MSH 2.2) in the run folder: the scene's boundaries and domain, and the new boundary ``opened`` (label 31 of
meshes/labels.py: both sides of every opened face); ``separated.json`` counts the separated bodies (connected
through faces that stayed closed) and gives their areas.
A continuous (CG) scene can run on it (``geometry.mesh = "separated.msh"``, ``boundary.opened``).

>>> import numpy as np
>>> pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
>>> tris = np.array([[0, 1, 2], [0, 2, 3]])
>>> p, t, opened, body = split(pts, tris, np.array([[0.5, 0.5]]))
>>> len(p), sorted(map(tuple, t.tolist())), len(opened), body.tolist()
(6, [(0, 1, 2), (4, 5, 3)], 2, [0, 1])
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..meshes import LABELS

OPENED = "opened"


class _Union:
    def __init__(self, n: int):
        self.parent = list(range(n))

    def find(self, a: int) -> int:
        while self.parent[a] != a:
            self.parent[a] = self.parent[self.parent[a]]
            a = self.parent[a]
        return a

    def join(self, a: int, b: int) -> None:
        self.parent[self.find(a)] = self.find(b)


def edge_owners(tris: np.ndarray) -> dict[tuple[int, int], list[int]]:
    """Sorted vertex pair -> the triangles that have it."""
    owners: dict[tuple[int, int], list[int]] = {}
    for t, (a, b, c) in enumerate(tris.tolist()):
        for e in ((a, b), (b, c), (c, a)):
            owners.setdefault((min(e), max(e)), []).append(t)
    return owners


def open_edges(points: np.ndarray, tris: np.ndarray, mids: np.ndarray) -> set[tuple[int, int]]:
    """The interior edges whose midpoints are ``mids`` (n, 2); an unmatched midpoint is an error."""
    from scipy.spatial import cKDTree

    owners = edge_owners(tris)
    keys = list(owners)
    if len(mids) == 0:
        return set()
    centre = np.array([(points[a, :2] + points[b, :2]) / 2 for a, b in keys])
    dist, idx = cKDTree(centre).query(mids[:, :2])
    scale = max(1.0, float(np.abs(points).max()))
    if dist.max() > 1e-9 * scale:
        raise ValueError(f"an opened face midpoint {mids[int(dist.argmax())]} matches no edge of the mesh")
    found = {keys[i] for i in idx}
    boundary = [k for k in found if len(owners[k]) != 2]
    if boundary:
        raise ValueError(f"opened faces must be interior edges; {boundary[0]} is on the boundary")
    return found


def split(points: np.ndarray, tris: np.ndarray, mids: np.ndarray):
    """Cut the triangle mesh along the interior edges with midpoints ``mids``.

    Returns (points, triangles, opened boundary segments (n, 2) in the new numbering, body index per triangle).
    """
    return cut(points, tris, open_edges(points, tris, mids))


def cut(points: np.ndarray, tris: np.ndarray, cut: set[tuple[int, int]]):
    """Cut the triangle mesh along the interior edges ``cut`` (sorted vertex pairs): :func:`split`'s result."""
    owners = edge_owners(tris)
    # per vertex: its triangles fall into groups joined through the edges at it that stay closed
    at: dict[int, list[int]] = {}
    for t, tri in enumerate(tris.tolist()):
        for v in tri:
            at.setdefault(v, []).append(t)
    new_points = [p for p in points]
    copy: dict[tuple[int, int], int] = {}          # (vertex, triangle) -> new vertex index
    for v, ts in at.items():
        u = _Union(len(ts))
        pos = {t: i for i, t in enumerate(ts)}
        for t in ts:
            for w in tris[t].tolist():
                if w == v:
                    continue
                key = (min(v, w), max(v, w))
                if key in cut:
                    continue
                for s in owners[key]:
                    if s != t and s in pos:
                        u.join(pos[t], pos[s])
        roots: dict[int, int] = {}
        for t in ts:
            r = u.find(pos[t])
            if r not in roots:
                roots[r] = v if not roots else len(new_points)
                if roots[r] != v:
                    new_points.append(points[v])
            copy[(v, t)] = roots[r]
    new_tris = np.array([[copy[(v, t)] for v in tri] for t, tri in enumerate(tris.tolist())], dtype=int)
    opened = np.array([[copy[(a, t)], copy[(b, t)]] for (a, b) in sorted(cut) for t in owners[(a, b)]],
                      dtype=int).reshape(-1, 2)
    bodies = _Union(len(tris))
    for key, ts in owners.items():
        if len(ts) == 2 and key not in cut:
            bodies.join(ts[0], ts[1])
    roots = [bodies.find(t) for t in range(len(tris))]
    order = {r: i for i, r in enumerate(dict.fromkeys(roots))}
    return np.array(new_points), new_tris, opened, np.array([order[r] for r in roots], dtype=int)


def write_msh(out: Path, points, tris, tri_tags, lines, line_tags, opened, names: dict) -> None:
    """MSH 2.2 of a cut triangle mesh: the boundary segments ``lines`` (tags ``line_tags``), both sides of the
    cut (``opened``, label 31) and the triangles; ``names``: (tag, dimension) -> physical name."""
    physical = [(1, t, names[(t, 1)]) for t in sorted({int(t) for t in line_tags}) if (t, 1) in names]
    physical += [(1, LABELS[OPENED], OPENED)]
    physical += [(2, t, names[(t, 2)]) for t in sorted({int(t) for t in tri_tags}) if (t, 2) in names]
    elements = [(1, LABELS[OPENED], s) for s in np.asarray(opened).tolist()] + \
        [(1, int(tag), s) for s, tag in zip(lines, line_tags)] + \
        [(2, int(tag), t) for t, tag in zip(np.asarray(tris).tolist(), np.asarray(tri_tags).tolist())]
    with open(out, "w") as f:
        f.write("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n")
        f.write(f"{len(physical)}\n" + "".join(f'{d} {t} "{n}"\n' for d, t, n in physical))
        f.write(f"$EndPhysicalNames\n$Nodes\n{len(points)}\n")
        f.write("".join(f"{i + 1} {p[0]:.17g} {p[1]:.17g} {p[2]:.17g}\n" for i, p in enumerate(points)))
        f.write(f"$EndNodes\n$Elements\n{len(elements)}\n")
        for i, (dim, tag, nodes) in enumerate(elements):
            kind = 1 if dim == 1 else 2
            f.write(f"{i + 1} {kind} 2 {tag} {tag} " + " ".join(str(n + 1) for n in nodes) + "\n")
        f.write("$EndElements\n")


def _read_tri_mesh(mesh_path: Path):
    """(mesh, points, triangles, their tags, boundary lines [(a, b)], their tags, (tag, dim) -> name)."""
    import meshio

    m = meshio.read(mesh_path, file_format="gmsh")
    tris = np.concatenate([b.data for b in m.cells if b.type == "triangle"])
    tri_tags = np.concatenate([m.cell_data["gmsh:physical"][i] for i, b in enumerate(m.cells) if b.type == "triangle"])
    lines, line_tags = [], []
    for i, b in enumerate(m.cells):
        if b.type == "line":
            lines += [tuple(e) for e in b.data.tolist()]
            line_tags += [int(t) for t in m.cell_data["gmsh:physical"][i].tolist()]
    names = {(int(v[0]), int(v[1])): k for k, v in m.field_data.items()}
    return m.points, tris, tri_tags, lines, line_tags, names


def _renumber_lines(tris, new_tris, lines):
    """Boundary segments of the uncut mesh in the numbering of the cut one (through the triangle owning each)."""
    owners = edge_owners(tris)
    out = []
    for a, c in lines:
        t = owners[(min(a, c), max(a, c))][0]
        pos = {v: k for k, v in enumerate(tris[t].tolist())}
        out.append((new_tris[t][pos[a]], new_tris[t][pos[c]]))
    return out


def reopen(mesh_path: Path):
    """Cut the mesh file along its segments labelled ``opened`` (interior edges, e.g. curves gmsh embedded) and
    write it back with both sides of the cut as ``opened``; returns (points, triangles) of the cut mesh."""
    points, tris, tri_tags, lines, line_tags, names = _read_tri_mesh(mesh_path)
    label = LABELS[OPENED]
    edges = {(min(a, b), max(a, b)) for (a, b), t in zip(lines, line_tags) if t == label}
    new_points, new_tris, opened, _ = cut(points, tris, edges)
    rest = [(e, t) for e, t in zip(lines, line_tags) if t != label]
    write_msh(mesh_path, new_points, new_tris, tri_tags, _renumber_lines(tris, new_tris, [e for e, _ in rest]),
              [t for _, t in rest], opened, names)
    return new_points, new_tris


def keep_held(mesh_path: Path, out: Path, held: set[int]) -> tuple[np.ndarray, np.ndarray]:
    """``out``: the cut mesh of ``mesh_path`` without the bodies that touch no boundary labelled in ``held``
    (a body that nothing holds has no static equilibrium); returns which triangles were kept and the old
    numbers of the vertices kept, in their new order."""
    points, tris, tri_tags, lines, line_tags, names = _read_tri_mesh(mesh_path)
    _, _, _, body = cut(points, tris, set())
    owner = {e: ts[0] for e, ts in edge_owners(tris).items()}
    line_body = [body[owner[(min(a, b), max(a, b))]] for a, b in lines]
    kept_bodies = {k for k, t in zip(line_body, line_tags) if t in held}
    keep = np.isin(body, sorted(kept_bodies))
    label = LABELS[OPENED]
    used = np.unique(tris[keep])
    new = np.full(len(points), -1)
    new[used] = np.arange(len(used))
    rest = [((new[a], new[b]), t) for (a, b), t, k in zip(lines, line_tags, line_body) if k in kept_bodies]
    write_msh(out, points[used], new[tris[keep]], np.asarray(tri_tags)[keep], [e for e, t in rest if t != label],
              [t for _, t in rest if t != label], [e for e, t in rest if t == label], names)
    return keep, used


def write_separated(mesh_path: Path, inc_dir: Path, out: Path) -> dict:
    """``out`` (MSH 2.2): the mesh of ``mesh_path`` cut along the faces opened by increment ``inc_dir``.

    Returns what it wrote: bodies and their areas (m^2), opened segments and their length (m)."""
    from .vtu import read_array

    points0, tris, tri_tags, lines, line_tags, names = _read_tri_mesh(mesh_path)
    mids = read_array(inc_dir / "dg_open_faces.txt").reshape(-1, 2)
    points, new_tris, opened, body = split(points0, tris, mids)
    if LABELS[OPENED] in set(line_tags):
        raise ValueError(f"{mesh_path}: already has the boundary '{OPENED}' (label {LABELS[OPENED]})")
    write_msh(out, points, new_tris, tri_tags, _renumber_lines(tris, new_tris, lines), line_tags, opened, names)
    p2 = points[:, :2]
    nb = int(body.max()) + 1
    e1, e2 = p2[new_tris[:, 1]] - p2[new_tris[:, 0]], p2[new_tris[:, 2]] - p2[new_tris[:, 0]]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    seg = np.linalg.norm(p2[opened[:, 1]] - p2[opened[:, 0]], axis=1) if len(opened) else np.zeros(0)
    report = {"increment": int(inc_dir.name.split("-")[-1]), "opened_faces": len(mids),
              "opened_segments": len(opened), "opened_length": float(seg.sum() / 2),
              "bodies": nb, "body_areas": [float(area[body == k].sum()) for k in range(nb)],
              "duplicated_vertices": len(points) - len(points0)}
    out.with_suffix(".json").write_text(json.dumps(report, indent=1))
    return report


def after_run(scene, files, state, progress) -> None:
    """A separating DG run: separated.msh, the mesh cut along the faces opened by the last increment."""
    dg = getattr(scene, "discretization", None)
    if dg is None or dg.separation_stress <= 0 or not state.accepted or state.segments[-1].get("discretization"):
        return          # (a run gone on with CG wrote it when it switched: wendel.loop.separated)
    inc = state.last[0]
    rep = write_separated(files.root / state.segment(inc)["mesh"], files.fem / f"inc-{inc:04d}",
                          files.root / "separated.msh")
    progress(f"  separated.msh: {rep['opened_faces']} opened faces (boundary '{OPENED}', {rep['opened_length']:.3g} m), "
             f"{rep['bodies']} bodies")
