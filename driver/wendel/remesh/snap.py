"""The tool where it stands at a remesh: the size zones that follow it, and a new mesh's boundary nodes moved
out of a rigid 2D tool (a rounded polygon).

The new boundary nodes lie on the old deformed boundary polygon (:mod:`wendel.remesh.mesher`). The contact is
node-to-surface, so an old boundary edge can pass through a convex tool while its two nodes are on or outside
it: on the cuts the machined surface stretches behind the rounded edge into edges of 30-45 um whose chords cut
the edge's corner, and the finer new mesh puts nodes on those chords, inside the tool. Measured on the F-bar
steel cut (edge radius 20 um, new edge cells 10 um): 1.3-3.4 um deep at each of 14 remeshes sampled; the
re-equilibration pushed them out, and the thrust force jumped by 10-15 % at each remesh and decayed over the
next 10 um of travel.

:func:`snap` moves such nodes to the closest point of the tool's surface, and the interior nodes around them
by a harmonic extension of that move (the moved cells stay valid; the move is halved until no cell inverts),
before the state is transferred. The tool is the contact module's: ``vertices`` (counter-clockwise) and a
corner radius per vertex (an arc tangent to both sides), placed by a shift.

>>> v = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
>>> p, d = closest(np.array([[1.0, 0.2], [1.9, 1.9]]), v, [0.0, 0.0, 1.0, 0.0])
>>> np.round(p, 6).tolist(), inside(np.array([[1.0, 0.2], [1.9, 1.9], [3.0, 1.0]]), v, [0.0, 0.0, 1.0, 0.0]).tolist()
([[1.0, 0.0], [1.707107, 1.707107]], [True, False, False])
"""

from __future__ import annotations

import math

import numpy as np

ARC_STEP = np.radians(0.25)      # the outline's arcs, for the inside test only (closest points are exact)


def _corners(vertices: np.ndarray, radii) -> list:
    """Per vertex: ``None`` for a sharp one, else its arc ``(centre, r, p_in, p_out)``, tangent to its two
    sides, from where the boundary arrives to where it leaves (the tool of ``edp/lib/tool.idp``)."""
    v = np.asarray(vertices, dtype=float)
    n, out = len(v), []
    for i in range(n):
        r = radii[i]
        if r <= 0:
            out.append(None)
            continue
        a, b = v[i - 1] - v[i], v[(i + 1) % n] - v[i]
        a, b = a / np.linalg.norm(a), b / np.linalg.norm(b)
        half = math.acos(np.clip(a @ b, -1, 1)) / 2
        centre = v[i] + (a + b) / np.linalg.norm(a + b) * r / math.sin(half)
        out.append((centre, r, v[i] + a * r / math.tan(half), v[i] + b * r / math.tan(half)))
    return out


def _pieces(vertices: np.ndarray, radii) -> tuple[list, list]:
    """The rounded polygon as straight segments ``(a, b)`` and arcs ``(centre, r, p_in, p_out)``."""
    v = np.asarray(vertices, dtype=float)
    corners = _corners(v, radii)
    ends = [(v[i], v[i]) if c is None else (c[2], c[3]) for i, c in enumerate(corners)]
    segments = [(ends[i][1], ends[(i + 1) % len(v)][0]) for i in range(len(v))]
    return segments, [c for c in corners if c is not None]


def outline(vertices, radii, per_arc: int | None = None) -> np.ndarray:
    """The rounded polygon as a closed polyline: ``per_arc`` points on each arc (default: one every
    ``ARC_STEP``), each arc the short way round through its corner."""
    v = np.asarray(vertices, dtype=float)
    out = []
    for i, c in enumerate(_corners(v, radii)):
        if c is None:
            out.append(v[i])
            continue
        centre, r, p0, p1 = c
        t0, t1 = math.atan2(*(p0 - centre)[::-1]), math.atan2(*(p1 - centre)[::-1])
        sweep = (t1 - t0 + math.pi) % (2 * math.pi) - math.pi
        k = per_arc or max(2, math.ceil(abs(sweep) / ARC_STEP)) + 1
        for t in t0 + np.linspace(0.0, sweep, k):
            out.append(centre + r * np.array([math.cos(t), math.sin(t)]))
    return np.array(out)


def inside(q: np.ndarray, vertices: np.ndarray, radii) -> np.ndarray:
    """Which points ``q`` (m, 2) are strictly inside the rounded polygon (crossing number on its outline)."""
    poly = outline(vertices, radii)
    a, b = poly, np.roll(poly, -1, axis=0)
    x, y = q[:, :1], q[:, 1:2]
    cross = ((a[:, 1] > y) != (b[:, 1] > y))
    with np.errstate(divide="ignore", invalid="ignore"):
        xi = a[:, 0] + (y - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (np.count_nonzero(cross & (x < xi), axis=1) % 2) == 1


def closest(q: np.ndarray, vertices: np.ndarray, radii) -> tuple[np.ndarray, np.ndarray]:
    """The closest points of the rounded polygon's boundary to the points ``q`` (m, 2), and their distances."""
    segments, arcs = _pieces(vertices, radii)
    best = np.full(len(q), np.inf)
    where = np.zeros_like(q, dtype=float)
    for a, b in segments:
        ab = b - a
        L2 = float(ab @ ab)
        t = np.clip(((q - a) @ ab) / L2, 0.0, 1.0) if L2 > 0 else np.zeros(len(q))
        p = a + t[:, None] * ab
        d = np.linalg.norm(q - p, axis=1)
        take = d < best
        best[take], where[take] = d[take], p[take]
    for c, r, p_in, p_out in arcs:
        e = q - c
        norm = np.linalg.norm(e, axis=1)
        ok = norm > 0
        s, f = p_in - c, p_out - c        # within the arc: counter-clockwise from s to f (less than pi)
        cs = s[0] * e[:, 1] - s[1] * e[:, 0]
        cf = e[:, 0] * f[1] - e[:, 1] * f[0]
        ok &= (cs >= 0) & (cf >= 0)
        p = c + r * e / np.where(norm > 0, norm, 1.0)[:, None]
        d = np.abs(norm - r)
        take = ok & (d < best)
        best[take], where[take] = d[take], p[take]
    return where, best


def snap(points: np.ndarray, cells: np.ndarray, boundary: np.ndarray, vertices: np.ndarray, radii,
         rings: int = 2, sweeps: int = 40) -> tuple[np.ndarray, dict]:
    """``points`` (n, 2) with the ``boundary`` nodes inside the tool moved onto its surface and the interior
    nodes within ``rings`` cell neighbourhoods of them moved by a harmonic extension (``sweeps`` Jacobi sweeps;
    other boundary nodes stay). Returns the points and ``{"nodes", "max_move", "scale"}`` (``scale`` < 1: the
    move was halved that often to keep every cell positive)."""
    from .quality import signed_measure

    pts = np.asarray(points, dtype=float)[:, :2]
    boundary = np.asarray(boundary, dtype=np.int64)
    ins = inside(pts[boundary], vertices, radii)
    if not ins.any():
        return pts.copy(), {"nodes": 0, "max_move": 0.0, "scale": 1.0}
    moved_nodes = boundary[ins]
    target, dist = closest(pts[moved_nodes], vertices, radii)
    move = np.zeros_like(pts)
    move[moved_nodes] = target - pts[moved_nodes]
    near = np.zeros(len(pts), dtype=bool)
    near[moved_nodes] = True
    for _ in range(rings):
        near[cells[near[cells].any(axis=1)].ravel()] = True
    free = near.copy()                                    # interior nodes near the moved ones
    free[boundary] = False
    if free.any():          # Jacobi on the graph Laplacian of the cells' edges out of the free nodes
        e = np.vstack([cells[:, [0, 1]], cells[:, [1, 2]], cells[:, [2, 0]]])
        e = np.vstack([e, e[:, ::-1]])
        e = e[free[e[:, 0]]]
        deg = np.bincount(e[:, 0], minlength=len(pts)).astype(float)
        for _ in range(sweeps):
            acc = np.zeros_like(pts)
            np.add.at(acc, e[:, 0], move[e[:, 1]])
            move[free] = acc[free] / deg[free, None]
    touched = near[cells].any(axis=1)
    scale = 1.0
    for _ in range(8):
        trial = pts + scale * move
        if np.all(signed_measure(np.hstack([trial, np.zeros((len(trial), 1))]), cells[touched]) > 0):
            return trial, {"nodes": int(len(moved_nodes)), "max_move": float(scale * dist.max()), "scale": scale}
        scale *= 0.5
    return pts.copy(), {"nodes": 0, "max_move": 0.0, "scale": 0.0}


def rewrite_nodes(path, points: np.ndarray) -> None:
    """Write ``points`` (n, 2 or 3), in the file's node order, into the ``$Nodes`` section of an ASCII MSH 2.2
    file, every other section as it was."""
    from pathlib import Path

    path = Path(path)
    text = path.read_bytes()
    a = text.index(b"$Nodes\n") + len(b"$Nodes\n")
    b = text.index(b"$EndNodes")
    lines = text[a:b].decode().splitlines()
    n = int(lines[0])
    if n != len(points):
        raise ValueError(f"{path}: {n} nodes, {len(points)} points given")
    pts = np.asarray(points, dtype=float)
    pts = np.hstack([pts, np.zeros((n, 3 - pts.shape[1]))]) if pts.shape[1] < 3 else pts
    body = "".join(f"{line.split(maxsplit=1)[0]} {x!r} {y!r} {z!r}\n"
                   for line, (x, y, z) in zip(lines[1:n + 1], pts.tolist()))
    path.write_bytes(text[:a] + f"{n}\n{body}".encode() + text[b:])


def tool_at(scene, inc_dir) -> dict:
    """The scene's rigid polygon tool (``contact.tool``: vertices and corner radii) where it stood at increment
    ``inc_dir`` (``tool_x``, ``tool_y`` of its record.json). For a scene with ``remesh.snap_to_tool``, which the
    schema accepts only with a convex 2D polygon tool that does not turn (``wendel.scene.schema.check_snap``)."""
    tool = scene.contact.tool
    v = np.asarray(tool.vertices, dtype=float)[:, :2] + placement(inc_dir)[0][:2]
    return {"vertices": v, "radii": list(tool.radii) if tool.radii else [0.0] * len(v)}


def onto_tool(mesh: "Path", points: np.ndarray, cells: np.ndarray, tool: dict) -> tuple[np.ndarray, dict]:
    """:func:`snap` on a new 2D mesh file (its boundary nodes against ``tool``, :func:`tool_at`), the file
    rewritten when a node moved; the points and the remesh report's keys ``tool_snapped_nodes``,
    ``tool_snap_max`` [m] and ``tool_snap_scale``."""
    from .mesher import boundary_facets

    pts, rep = snap(points, cells, np.unique(boundary_facets(cells)), tool["vertices"], tool["radii"])
    if rep["nodes"]:
        rewrite_nodes(mesh, pts)
    return pts, {"tool_snapped_nodes": rep["nodes"], "tool_snap_max": rep["max_move"], "tool_snap_scale": rep["scale"]}


def zones_at(r, inc_dir) -> list[dict]:
    """The size zones of ``remesh`` (``r``) for the remesh after increment ``inc_dir``: as written, or moved by
    the tool's placement (``tool_x``, ``tool_y``(, ``tool_z``) of its record.json) when they follow the tool."""
    shift = placement(inc_dir)[0] if r.zones and r.zones_follow == "tool" else np.zeros(3)
    return [{"box": [[c + d for c, d in zip(corner, shift)] for corner in z.box], "h": z.h, "thickness": z.thickness}
            for z in r.zones]


def trim_at(r, inc_dir) -> dict | None:
    """``remesh.trim`` of ``remesh`` (``r``) for the remesh after increment ``inc_dir`` (its point moved with the tool
    as the zones are, :func:`zones_at`), as :func:`wendel.remesh.mesher.remesh` takes it; None without one."""
    t = r.trim
    if t is None:
        return None
    shift = placement(inc_dir)[0] if r.zones_follow == "tool" else np.zeros(3)
    return {"point": [t.point[0] + shift[0], t.point[1] + shift[1]], "radius": t.radius,
            "above": t.above + shift[1], "label": t.label}


def placement(inc_dir) -> tuple[np.ndarray, float]:
    """The tool's placement at increment ``inc_dir``: its shift (``tool_x``, ``tool_y``, ``tool_z`` of its
    record.json, 0 where missing or empty) and turn (``tool_angle``)."""
    import json

    rec = json.loads((inc_dir / "record.json").read_text())
    return np.array([float(rec.get(f"tool_{a}") or 0.0) for a in "xyz"]), float(rec.get("tool_angle") or 0.0)
