"""Parametric gmsh builders (Python API), registered by name.

>>> {"box", "disk"} <= set(BUILDERS)
True
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Callable

from .labels import LABELS

BUILDERS: dict[str, Callable[..., "Built"]] = {}
# The boundary names a builder labels, as a function of its parameters (builders that declare them).
BOUNDARIES: dict[str, Callable[..., list[str]]] = {}


@dataclasses.dataclass
class Built:
    """What a builder made: the file, the dimension and the boundary names it labelled."""

    path: Path
    dimension: int
    boundaries: list[str]
    nodes: int
    elements: int
    # from the mesh cache (wendel.meshes.cache): {"dir", "key", "hit"}; None when the cache is off
    cache: dict | None = None


def register(name: str, boundaries: list[str] | Callable[..., list[str]] | None = None):
    """Register a builder under ``name`` (used as ``geometry.builder`` in scene files).

    ``boundaries`` names the boundaries it labels (a list, or a function of the builder's keywords), so a
    scene's boundary names are checked before anything is meshed.
    """

    def wrap(func):
        BUILDERS[name] = func
        if boundaries is not None:
            BOUNDARIES[name] = boundaries if callable(boundaries) else (lambda **_: list(boundaries))
        return func

    return wrap


def build(name: str, path: Path, **params) -> Built:
    """Run builder ``name`` and write its mesh to ``path`` (MSH 2.2), through the mesh cache when
    ``WENDEL_MESH_CACHE`` is set (:mod:`wendel.meshes.cache`)."""
    if name not in BUILDERS:
        raise KeyError(f"unknown geometry builder {name!r}; valid: {', '.join(sorted(BUILDERS))}")
    from . import cache

    return cache.build(name, Path(path), params, BUILDERS[name])


def start_gmsh():
    """Initialize gmsh (quiet, one thread, reproducible) without taking over the process's signals.

    gmsh's initialize resets SIGINT and SIGTERM to their defaults at the C level (also with
    ``interruptible=False``), so Ctrl-C and SIGTERM would kill the driver at once and leave FreeFEM
    running: Python's handlers are installed again afterwards.
    """
    import signal

    import gmsh

    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    gmsh.initialize(["-noenv"], readConfigFiles=False, interruptible=False)
    for s, h in handlers.items():
        signal.signal(s, h if h is not None else signal.SIG_DFL)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.option.setNumber("Mesh.RandomSeed", 1)
    return gmsh


class _Session:
    """A gmsh session that always finalizes, quiet unless asked."""

    def __init__(self, name: str):
        self.name = name

    def __enter__(self):
        gmsh = start_gmsh()
        gmsh.model.add(self.name)
        self.gmsh = gmsh
        return gmsh

    def __exit__(self, *exc):
        self.gmsh.finalize()
        return False


def _size_field(gmsh, h: float, refine: dict | None):
    """Uniform size ``h``, or ``h`` graded down to ``refine['h']`` near a point (a ball of radius r), or
    inside a block ``refine['box'] = [lo, hi]`` (corners; a flat block is a layer), graded over ``thickness``.
    The fine size is ``refine['h']``, or ``refine['ratio'] * h`` (then it follows h in studies and smoke runs)."""
    if not refine:
        gmsh.option.setNumber("Mesh.MeshSizeMin", h)
        gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        return
    f = gmsh.model.mesh.field
    h_in = refine["h"] if "h" in refine else h * refine["ratio"]
    if "box" in refine:
        # a layer or block [lo, hi] (e.g. the contact face of a stamp), graded over `thickness`
        lo, hi = refine["box"]
        box = f.add("Box")
        for key, v in zip(("XMin", "YMin", "ZMin", "XMax", "YMax", "ZMax"), list(lo) + [0.0] * (3 - len(lo)) + list(hi) + [0.0] * (3 - len(hi))):
            f.setNumber(box, key, v)
        f.setNumber(box, "Thickness", refine.get("thickness", 0.0))
        f.setNumber(box, "VIn", h_in)
        f.setNumber(box, "VOut", h)
        f.setAsBackgroundMesh(box)
    else:
        ball = f.add("Ball")
        c = refine["center"]
        f.setNumber(ball, "XCenter", c[0])
        f.setNumber(ball, "YCenter", c[1])
        f.setNumber(ball, "ZCenter", c[2] if len(c) > 2 else 0.0)
        f.setNumber(ball, "Radius", refine["radius"])
        f.setNumber(ball, "Thickness", refine.get("thickness", refine["radius"]))
        f.setNumber(ball, "VIn", h_in)
        f.setNumber(ball, "VOut", h)
        f.setAsBackgroundMesh(ball)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)


ALGORITHMS_3D = {"delaunay": 1, "hxt": 10}
"""gmsh's ``Mesh.Algorithm3D`` by the builders' ``algorithm`` keyword (HXT on one thread: the same mesh every run)."""


def _write(gmsh, path: Path, dimension: int, boundaries: list[str], optimize: bool = True,
           algorithm: str = "delaunay", optimize_threshold: float = 0.3) -> Built:
    if dimension == 3:
        gmsh.option.setNumber("Mesh.Algorithm3D", ALGORITHMS_3D[algorithm])
        gmsh.option.setNumber("Mesh.OptimizeThreshold", optimize_threshold)   # gmsh's own pass, in generate(3)
    gmsh.model.mesh.generate(dimension)
    if dimension == 3 and optimize:
        gmsh.model.mesh.optimize("Netgen")
    gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    path.parent.mkdir(parents=True, exist_ok=True)
    gmsh.write(str(path))
    nodes = len(gmsh.model.mesh.getNodes()[0])
    types, tags, _ = gmsh.model.mesh.getElements(dimension)
    elements = sum(len(t) for t in tags)
    return Built(path, dimension, boundaries, nodes, elements)


def _tag_boxes(gmsh, dim: int, lo, hi, names: list[str]):
    """Put the boundary entities of a box/rectangle into named physical groups by their position."""
    tol = 1e-6 * max(h - l for l, h in zip(lo, hi)) + 1e-6  # OCC pads bounding boxes by 1e-7
    groups: dict[str, list[int]] = {n: [] for n in names}
    axes = [("left", "right"), ("bottom", "top")] if dim == 2 else [("left", "right"), ("front", "back"), ("bottom", "top")]
    for _, tag in gmsh.model.getEntities(dim - 1):
        bb = gmsh.model.getBoundingBox(dim - 1, tag)
        bmin, bmax = bb[:3], bb[3:]
        for axis, (low_name, high_name) in enumerate(axes):
            if abs(bmax[axis] - bmin[axis]) < tol:
                name = low_name if abs(bmin[axis] - lo[axis]) < tol else high_name
                groups[name].append(tag)
    for name, tags in groups.items():
        gmsh.model.addPhysicalGroup(dim - 1, tags, LABELS[name], name)
    vols = [t for _, t in gmsh.model.getEntities(dim)]
    gmsh.model.addPhysicalGroup(dim, vols, LABELS["domain"], "domain")


def rectangle_sizes(gmsh, x, y, h: float, refine: dict | None, structured: bool) -> None:
    """The rectangle [x0, x1] x [y0, y1] and its sizes: transfinite (``structured``, right-leaning
    diagonals) or ``h`` with an optional refined zone (plane and (r, z) rectangles alike)."""
    gmsh.model.occ.addRectangle(x[0], y[0], 0.0, x[1] - x[0], y[1] - y[0])
    gmsh.model.occ.synchronize()
    if structured:
        for _, c in gmsh.model.getEntities(1):
            bb = gmsh.model.getBoundingBox(1, c)
            length = max(bb[3] - bb[0], bb[4] - bb[1])
            gmsh.model.mesh.setTransfiniteCurve(c, max(2, round(length / h) + 1))
        for _, s in gmsh.model.getEntities(2):
            gmsh.model.mesh.setTransfiniteSurface(s)
    else:
        _size_field(gmsh, h, refine)


@register("rectangle", ["left", "right", "bottom", "top"])
def rectangle(path: Path, x=(0.0, 1.0), y=(0.0, 1.0), h=0.1, refine=None, structured=False) -> Built:
    """A rectangle [x0, x1] x [y0, y1] (m) with boundaries left, right, bottom, top.

    ``structured=True`` gives a transfinite mesh (right-leaning diagonals), useful for convergence studies.
    """
    names = ["left", "right", "bottom", "top"]
    with _Session("rectangle") as gmsh:
        rectangle_sizes(gmsh, x, y, h, refine, structured)
        _tag_boxes(gmsh, 2, (x[0], y[0]), (x[1], y[1]), names)
        return _write(gmsh, path, 2, names)


@register("box", ["left", "right", "front", "back", "bottom", "top"])
def box(path: Path, x=(0.0, 1.0), y=(0.0, 1.0), z=(0.0, 1.0), h=0.1, refine=None, optimize=True,
        algorithm="delaunay", optimize_threshold=0.3) -> Built:
    """A box [x0, x1] x [y0, y1] x [z0, z1] (m) with boundaries left, right, front, back, bottom, top.

    ``optimize = False`` skips gmsh's Netgen optimization of the tetrahedra (most of the 3D meshing time:
    `wendel bench gmsh3d`): another, faster mesh with a worse worst element. ``algorithm = "hxt"`` meshes the
    volume with gmsh's HXT instead of its Delaunay (faster again: `wendel bench gmsh3d`). ``optimize_threshold``:
    gmsh's own optimizer reworks the tetrahedra of quality below it (0.3, gmsh's default; hertz-force-3d: 0.6)."""
    names = ["left", "right", "front", "back", "bottom", "top"]
    with _Session("box") as gmsh:
        occ = gmsh.model.occ
        occ.addBox(x[0], y[0], z[0], x[1] - x[0], y[1] - y[0], z[1] - z[0])
        occ.synchronize()
        _size_field(gmsh, h, refine)
        _tag_boxes(gmsh, 3, (x[0], y[0], z[0]), (x[1], y[1], z[1]), names)
        return _write(gmsh, path, 3, names, optimize=optimize, algorithm=algorithm,
                      optimize_threshold=optimize_threshold)


@register("ring", lambda quarter=True, **_: ["inner", "outer"] + (["symmetry_x", "symmetry_y"] if quarter else []))
def ring(path: Path, r_inner=1.0, r_outer=1.3, h=0.05, quarter=True) -> Built:
    """A thick-walled cylinder cross-section (plane strain): a quarter ring by default.

    Boundaries: inner, outer, and for the quarter the symmetry planes symmetry_x (x = 0) and symmetry_y (y = 0).
    """
    with _Session("ring") as gmsh:
        occ = gmsh.model.occ
        outer = occ.addDisk(0, 0, 0, r_outer, r_outer)
        inner = occ.addDisk(0, 0, 0, r_inner, r_inner)
        shape, _ = occ.cut([(2, outer)], [(2, inner)])
        if quarter:
            clip = occ.addRectangle(0, 0, 0, 2 * r_outer, 2 * r_outer)
            shape, _ = occ.intersect(shape, [(2, clip)])
        occ.synchronize()
        _size_field(gmsh, h, None)
        groups = {"inner": [], "outer": [], "symmetry_x": [], "symmetry_y": []}
        for _, c in gmsh.model.getEntities(1):
            lo, hi = gmsh.model.getParametrizationBounds(1, c)
            px, py, _ = gmsh.model.getValue(1, c, [(lo[0] + hi[0]) / 2])
            r = math.hypot(px, py)
            if abs(r - r_inner) < 1e-6 * r_outer:
                groups["inner"].append(c)
            elif abs(r - r_outer) < 1e-6 * r_outer:
                groups["outer"].append(c)
            elif abs(px) < 1e-6 * r_outer:
                groups["symmetry_x"].append(c)
            else:
                groups["symmetry_y"].append(c)
        names = [n for n, t in groups.items() if t]
        for n in names:
            gmsh.model.addPhysicalGroup(1, groups[n], LABELS[n], n)
        gmsh.model.addPhysicalGroup(2, [t for _, t in gmsh.model.getEntities(2)], LABELS["domain"], "domain")
        return _write(gmsh, path, 2, names)


@register("disk", ["outer"])
def disk(path: Path, radius=1.0, center=(0.0, 0.0), h=0.1) -> Built:
    """A full disk of ``radius`` (m) around ``center``: a bar's circular cross-section; boundary outer."""
    with _Session("disk") as gmsh:
        occ = gmsh.model.occ
        occ.addDisk(center[0], center[1], 0, radius, radius)
        occ.synchronize()
        _size_field(gmsh, h, None)
        curves = [c for _, c in gmsh.model.getEntities(1)]
        gmsh.model.addPhysicalGroup(1, curves, LABELS["outer"], "outer")
        gmsh.model.addPhysicalGroup(2, [t for _, t in gmsh.model.getEntities(2)], LABELS["domain"], "domain")
        return _write(gmsh, path, 2, ["outer"])


@register("parallelogram", ["left", "right", "bottom", "top"])
def parallelogram(path: Path, x=(0.0, 1.0), y=(0.0, 1.0), slope=0.0, h=0.1) -> Built:
    """The rectangle [x0, x1] x [y0, y1] (m) sheared vertically by ``slope`` (1): the point (x, y) moves to
    (x, y + slope (x - x0)); a block resting on an incline of angle atan(slope). Boundaries left and right
    (vertical), bottom and top (inclined)."""
    names = ["left", "right", "bottom", "top"]
    with _Session("parallelogram") as gmsh:
        occ = gmsh.model.occ
        rise = slope * (x[1] - x[0])
        p = [occ.addPoint(x[0], y[0], 0), occ.addPoint(x[1], y[0] + rise, 0),
             occ.addPoint(x[1], y[1] + rise, 0), occ.addPoint(x[0], y[1], 0)]
        lines = {"bottom": occ.addLine(p[0], p[1]), "right": occ.addLine(p[1], p[2]),
                 "top": occ.addLine(p[2], p[3]), "left": occ.addLine(p[3], p[0])}
        loop = occ.addCurveLoop([lines["bottom"], lines["right"], lines["top"], lines["left"]])
        surf = occ.addPlaneSurface([loop])
        occ.synchronize()
        _size_field(gmsh, h, None)
        for n in names:
            gmsh.model.addPhysicalGroup(1, [lines[n]], LABELS[n], n)
        gmsh.model.addPhysicalGroup(2, [surf], LABELS["domain"], "domain")
        return _write(gmsh, path, 2, names)
