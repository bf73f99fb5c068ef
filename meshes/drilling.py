"""Drilled workpieces: material removal by geometry (gmsh OpenCASCADE booleans).

A twist drill of diameter ``D = 2 R`` and point angle ``sigma`` (118 deg for a standard drill) with its
tip at depth ``d`` below the entry face removes the set

    B(d) = { r <= R, 0 <= s <= d - r cot(kappa) },   kappa = sigma / 2,

where ``r`` is the distance from the drill axis and ``s`` the depth below the entry face (the bore is the
drill's envelope: a cylinder closed by the tip cone of height ``h_c = R cot(kappa)``; ``d`` is the depth
of the tip). Its volume (:func:`bore_volume`) is

    V(d) = pi R^2 (d - h_c) + pi R^2 h_c / 3          for d >= h_c,
    V(d) = pi (d tan kappa)^2 d / 3                    for d <  h_c (the cone alone).

3D (:func:`drilled`, builders ``drilled-cylinder`` and ``drilled-block``): the workpiece occupies
``0 <= z <= H``, the entry face is ``z = H`` and the drill axis is the vertical line through
``axis = (x_a, y_a)``. 2D (:func:`drilled_section`, builder ``drilled-section``): the axisymmetric
(r, z) section ``[0, R_w] x [0, H]`` minus the bore profile, for the axisymmetric scenes.

After a boolean the order and numbering of entities is not documented, so every boundary entity is
classified by its geometry (centre, points on it, bounding box): bore wall (r = R), bore bottom (the tip
cone), entry face (top, z = H), base (bottom, z = 0), outer faces (outer for a cylinder, left/right/
front/back for a block; in 2D outer at r = R_w and axis on r = 0 below the bore).
The mesh is graded towards the bore wall and bottom: size ``h_bore`` there, growing to ``h`` over the
distance ``grade``.

>>> round(bore_volume(10.0, 1.0, 90.0) / math.pi, 9)      # h_c = 1: pi (10 - 1) + pi / 3
9.333333333
>>> round(bore_volume(0.5, 1.0, 90.0) / math.pi, 9)       # inside the cone: pi 0.5^2 0.5 / 3
0.041666667
"""

from __future__ import annotations

import math
from pathlib import Path

from .builders import Built, _Session, _write, register
from .labels import LABELS

BORE = ("bore_wall", "bore_bottom")


def cone_height(radius: float, point_angle: float) -> float:
    """Height of the tip cone, ``R cot(sigma / 2)`` (m); ``point_angle`` in degrees."""
    return radius / math.tan(math.radians(point_angle) / 2)


def bore_volume(depth: float, radius: float, point_angle: float) -> float:
    """Volume (m^3) of the bore of a drill of radius ``radius`` with its tip at ``depth`` below the face."""
    if depth <= 0:
        return 0.0
    hc = cone_height(radius, point_angle)
    if depth >= hc:
        return math.pi * radius ** 2 * (depth - hc / 1.5)
    r = depth * radius / hc
    return math.pi * r ** 2 * depth / 3


def bore_areas(depth: float, radius: float, point_angle: float) -> tuple[float, float]:
    """(wall, bottom) areas (m^2) of the bore: cylinder of height ``depth - h_c`` and the wetted cone."""
    if depth <= 0:
        return 0.0, 0.0
    hc = cone_height(radius, point_angle)
    r = min(radius, depth * radius / hc)
    slant = math.hypot(r, min(depth, hc))
    return 2 * math.pi * radius * max(0.0, depth - hc), math.pi * r * slant


def _check(depth, diameter, point_angle, height):
    if not 0 < point_angle < 180:
        raise ValueError(f"point_angle must be in (0, 180) degrees, got {point_angle}")
    if diameter <= 0:
        raise ValueError(f"diameter must be > 0 m, got {diameter}")
    if not 0 <= depth < height:
        raise ValueError(f"depth must be in [0, {height}) m (the workpiece height), got {depth}")


def _grading(gmsh, h: float, h_bore: float, grade: float, surfaces: list[int], dim: int):
    """Size h_bore on the bore surfaces, growing linearly to h over the distance grade."""
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    if not surfaces or h_bore >= h:
        gmsh.option.setNumber("Mesh.MeshSizeMin", h)
        return
    f = gmsh.model.mesh.field
    dist = f.add("Distance")
    f.setNumbers(dist, "SurfacesList" if dim == 3 else "CurvesList", surfaces)
    f.setNumber(dist, "Sampling", 30)
    thr = f.add("Threshold")
    f.setNumber(thr, "InField", dist)
    f.setNumber(thr, "SizeMin", h_bore)
    f.setNumber(thr, "SizeMax", h)
    f.setNumber(thr, "DistMin", 0.0)
    f.setNumber(thr, "DistMax", grade)
    f.setAsBackgroundMesh(thr)


def drilled(path: Path, workpiece: str = "cylinder", depth: float = 0.0, diameter: float = 0.01,
            point_angle: float = 118.0, radius: float = 0.02, x=(-0.02, 0.02), y=(-0.02, 0.02),
            height: float = 0.03, axis=(0.0, 0.0), h: float = 0.004, h_bore: float | None = None,
            grade: float | None = None) -> Built:
    """A 3D workpiece (``cylinder`` of ``radius`` or ``block`` [x] x [y], height ``height``, m) with the bore
    of a drill of ``diameter`` (m) and ``point_angle`` (deg) whose tip is ``depth`` (m) below the face z = H.

    Boundaries: bore_wall, bore_bottom (absent while depth = 0), top, bottom, and outer (cylinder) or
    left/right/front/back (block). ``h_bore`` (default h/3) is the size at the bore, graded to ``h`` over
    ``grade`` (default 2 D).
    """
    _check(depth, diameter, point_angle, height)
    R, H = diameter / 2, height
    h_bore = h_bore or h / 3
    grade = grade or 2 * diameter
    if workpiece == "cylinder":
        if radius <= R + abs(axis[0]) + abs(axis[1]):
            raise ValueError(f"radius {radius} m leaves no wall around the bore of diameter {diameter} m")
        sides = ["outer"]
    elif workpiece == "block":
        if not (x[0] < axis[0] - R and axis[0] + R < x[1] and y[0] < axis[1] - R and axis[1] + R < y[1]):
            raise ValueError(f"the bore (axis {list(axis)}, diameter {diameter} m) does not fit in the block")
        sides = ["left", "right", "front", "back"]
    else:
        raise ValueError(f"unknown workpiece {workpiece!r}; valid: cylinder, block")
    hc = cone_height(R, point_angle)
    with _Session("drilled") as gmsh:
        occ = gmsh.model.occ
        body = occ.addCylinder(0, 0, 0, 0, 0, H, radius) if workpiece == "cylinder" else \
            occ.addBox(x[0], y[0], 0, x[1] - x[0], y[1] - y[0], H)
        if depth > 0:
            zt = H - depth
            cone = occ.addCone(axis[0], axis[1], zt, 0, 0, hc, 0.0, R)
            top = H + 0.1 * H + hc
            shank = occ.addCylinder(axis[0], axis[1], zt + hc, 0, 0, top - zt - hc, R)
            drill, _ = occ.fuse([(3, cone)], [(3, shank)])
            occ.cut([(3, body)], drill)
        occ.synchronize()
        groups = _classify_3d(gmsh, R, H, axis, workpiece, radius, x, y)
        bore = groups["bore_wall"] + groups["bore_bottom"]
        _grading(gmsh, h, h_bore, grade, bore, 3)
        names = [n for n in (*BORE, "top", "bottom", *sides) if groups.get(n)]
        for n in names:
            gmsh.model.addPhysicalGroup(2, groups[n], LABELS[n], n)
        gmsh.model.addPhysicalGroup(3, [t for _, t in gmsh.model.getEntities(3)], LABELS["domain"], "domain")
        return _write(gmsh, Path(path), 3, names)


def _samples(gmsh, dim: int, tag: int) -> list[tuple[float, ...]]:
    """Points of a curve (3) or surface (3 x 3) at fractions of its parameter range."""
    lo, hi = gmsh.model.getParametrizationBounds(dim, tag)
    fr = (0.1, 0.5, 0.9)
    if dim == 1:
        par = [lo[0] + a * (hi[0] - lo[0]) for a in fr]
    else:
        par = [v for a in fr for b in fr for v in (lo[0] + a * (hi[0] - lo[0]), lo[1] + b * (hi[1] - lo[1]))]
    xyz = gmsh.model.getValue(dim, tag, par)
    return [tuple(xyz[3 * i:3 * i + 3]) for i in range(len(xyz) // 3)]


def _classify_3d(gmsh, R, H, axis, workpiece, radius, x, y) -> dict[str, list[int]]:
    """Name each surface by points on it (exact geometry; bounding boxes are padded by OCC)."""
    tol = 1e-6 * max(H, radius, abs(x[1] - x[0]), abs(y[1] - y[0]))
    groups: dict[str, list[int]] = {n: [] for n in (*BORE, "top", "bottom", "outer", "left", "right", "front", "back")}
    for _, s in gmsh.model.getEntities(2):
        pts = _samples(gmsh, 2, s)
        rs = [math.hypot(p[0] - axis[0], p[1] - axis[1]) for p in pts]
        on = lambda k, v: all(abs(p[k] - v) < tol for p in pts)
        if on(2, H):
            name = "top"
        elif on(2, 0.0):
            name = "bottom"
        elif all(abs(r - R) < tol for r in rs):
            name = "bore_wall"
        elif all(r < R + tol for r in rs):
            name = "bore_bottom"
        elif workpiece == "cylinder":
            name = "outer"
        else:
            name = next(n for n, k, v in (("left", 0, x[0]), ("right", 0, x[1]), ("front", 1, y[0]), ("back", 1, y[1]))
                        if on(k, v))
        groups[name].append(s)
    return groups


def drilled_section(path: Path, depth: float = 0.0, diameter: float = 0.01, point_angle: float = 118.0,
                    radius: float = 0.02, height: float = 0.03, h: float = 0.004, h_bore: float | None = None,
                    grade: float | None = None) -> Built:
    """The axisymmetric (r, z) section: the rectangle [0, radius] x [0, height] (x = r, y = z, m) minus the
    bore profile of a drill with its tip ``depth`` below the face z = H.

    Boundaries: bore_wall (r = R), bore_bottom (the cone's generatrix), top, bottom, outer (r = radius) and
    axis (r = 0 below the tip; the axisymmetric model pins u_r = 0 there by itself).
    """
    _check(depth, diameter, point_angle, height)
    R, H = diameter / 2, height
    if radius <= R:
        raise ValueError(f"radius {radius} m leaves no wall around the bore of diameter {diameter} m")
    h_bore = h_bore or h / 3
    grade = grade or 2 * diameter
    hc = cone_height(R, point_angle)
    with _Session("drilled_section") as gmsh:
        occ = gmsh.model.occ
        body = occ.addRectangle(0, 0, 0, radius, H)
        if depth > 0:
            zt = H - depth
            top = H + 0.1 * H + hc
            pts = [occ.addPoint(0, zt, 0), occ.addPoint(R, zt + hc, 0), occ.addPoint(R, top, 0), occ.addPoint(0, top, 0)]
            lines = [occ.addLine(pts[i], pts[(i + 1) % 4]) for i in range(4)]
            drill = occ.addPlaneSurface([occ.addCurveLoop(lines)])
            occ.cut([(2, body)], [(2, drill)])
        occ.synchronize()
        tol = 1e-6 * max(H, radius)
        groups: dict[str, list[int]] = {n: [] for n in (*BORE, "top", "bottom", "outer", "axis")}
        for _, c in gmsh.model.getEntities(1):
            pts = _samples(gmsh, 1, c)
            on = lambda k, v: all(abs(p[k] - v) < tol for p in pts)
            name = ("top" if on(1, H) else "bottom" if on(1, 0.0) else "outer" if on(0, radius) else
                    "axis" if on(0, 0.0) else "bore_wall" if on(0, R) else "bore_bottom")
            groups[name].append(c)
        _grading(gmsh, h, h_bore, grade, groups["bore_wall"] + groups["bore_bottom"], 2)
        names = [n for n in (*BORE, "top", "bottom", "outer", "axis") if groups[n]]
        for n in names:
            gmsh.model.addPhysicalGroup(1, groups[n], LABELS[n], n)
        gmsh.model.addPhysicalGroup(2, [t for _, t in gmsh.model.getEntities(2)], LABELS["domain"], "domain")
        return _write(gmsh, Path(path), 2, names)


@register("drilled-cylinder", boundaries=["bore_wall", "bore_bottom", "top", "bottom", "outer"])
def drilled_cylinder(path: Path, depth=0.0, diameter=0.01, point_angle=118.0, radius=0.02, height=0.03,
                     h=0.004, h_bore=None, grade=None) -> Built:
    """A cylinder workpiece (radius, height; m) with the bore of a drill whose tip is ``depth`` below z = H."""
    return drilled(path, "cylinder", depth, diameter, point_angle, radius=radius, height=height, h=h,
                   h_bore=h_bore, grade=grade)


@register("drilled-block", boundaries=["bore_wall", "bore_bottom", "top", "bottom", "left", "right", "front", "back"])
def drilled_block(path: Path, depth=0.0, diameter=0.01, point_angle=118.0, x=(-0.02, 0.02), y=(-0.02, 0.02),
                  height=0.03, axis=(0.0, 0.0), h=0.004, h_bore=None, grade=None) -> Built:
    """A block workpiece [x] x [y] x [0, height] (m) with the bore of a drill along the vertical ``axis``."""
    return drilled(path, "block", depth, diameter, point_angle, x=x, y=y, height=height, axis=axis, h=h,
                   h_bore=h_bore, grade=grade)


@register("drilled-section", boundaries=["bore_wall", "bore_bottom", "top", "bottom", "outer", "axis"])
def drilled_section_builder(path: Path, depth=0.0, diameter=0.01, point_angle=118.0, radius=0.02, height=0.03,
                            h=0.004, h_bore=None, grade=None) -> Built:
    """The axisymmetric (r, z) section of a drilled cylinder (for axisymmetric scenes)."""
    return drilled_section(path, depth, diameter, point_angle, radius, height, h, h_bore, grade)
