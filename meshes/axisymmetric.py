"""Builders of axisymmetric (r, z) sections: x = r >= 0, y = z; the axis x = 0 is the boundary ``axis``.

FreeFEM pins u_r = 0 on ``axis`` by itself (edp/lib/axisymmetric-mechanics.idp); every other boundary is
named as in the plane builders.

>>> from meshes.builders import BUILDERS
>>> {"axi_rectangle", "hollow_cylinder_section", "notched_bar", "sphere_section"} <= set(BUILDERS)
True
"""

from __future__ import annotations

import math
from pathlib import Path

from .builders import Built, _Session, _size_field, _write, rectangle_sizes, register
from .labels import LABELS


def _name_curves(gmsh, classify) -> list[str]:
    """Physical groups of the boundary curves by ``classify(x, y, length) -> name`` at each curve's midpoint."""
    groups: dict[str, list[int]] = {}
    for _, c in gmsh.model.getEntities(1):
        lo, hi = gmsh.model.getParametrizationBounds(1, c)
        px, py, _ = gmsh.model.getValue(1, c, [(lo[0] + hi[0]) / 2])
        groups.setdefault(classify(px, py), []).append(c)
    for name, tags in groups.items():
        gmsh.model.addPhysicalGroup(1, tags, LABELS[name], name)
    gmsh.model.addPhysicalGroup(2, [t for _, t in gmsh.model.getEntities(2)], LABELS["domain"], "domain")
    return sorted(groups)


@register("axi_rectangle", lambda r=(0.0, 1.0), **_: ["axis" if r[0] == 0 else "left", "right", "bottom", "top"])
def axi_rectangle(path: Path, r=(0.0, 1.0), z=(0.0, 1.0), h=0.1, refine=None, structured=False) -> Built:
    """A rectangle [r0, r1] x [z0, z1] (m) of an (r, z) section: boundaries axis (r = 0; ``left`` when
    r0 > 0), right, bottom, top. ``structured=True``: a transfinite mesh (convergence studies)."""
    with _Session("axi_rectangle") as gmsh:
        rectangle_sizes(gmsh, r, z, h, refine, structured)
        tol = 1e-6 * max(r[1] - r[0], z[1] - z[0])

        def classify(px, py):
            if abs(px - r[0]) < tol:
                return "axis" if abs(r[0]) < tol else "left"
            if abs(px - r[1]) < tol:
                return "right"
            return "bottom" if abs(py - z[0]) < tol else "top"

        names = _name_curves(gmsh, classify)
        return _write(gmsh, path, 2, names)


@register("hollow_cylinder_section", ["inner", "outer", "bottom", "top"])
def hollow_cylinder_section(path: Path, r_inner=1.0, r_outer=2.0, z=(0.0, 1.0), h=0.1, refine=None) -> Built:
    """The (r, z) section of a hollow cylinder (a bore of radius ``r_inner``): [r_inner, r_outer] x [z0, z1] (m);
    boundaries inner, outer, bottom, top (no axis)."""
    if not 0 < r_inner < r_outer:
        raise ValueError(f"hollow_cylinder_section needs 0 < r_inner < r_outer, got {r_inner}, {r_outer}")
    with _Session("hollow_cylinder_section") as gmsh:
        occ = gmsh.model.occ
        occ.addRectangle(r_inner, z[0], 0.0, r_outer - r_inner, z[1] - z[0])
        occ.synchronize()
        _size_field(gmsh, h, refine)
        tol = 1e-6 * r_outer

        def classify(px, py):
            if abs(px - r_inner) < tol:
                return "inner"
            if abs(px - r_outer) < tol:
                return "outer"
            return "bottom" if abs(py - z[0]) < tol else "top"

        return _write(gmsh, path, 2, _name_curves(gmsh, classify))


@register("sphere_section", lambda r_inner=0.0, half=False, **_: ["axis", "outer"] + (["inner"] if r_inner > 0 else []) + ([] if half else ["symmetry_y"]))
def sphere_section(path: Path, r_inner=0.0, r_outer=1.0, h=0.05, refine=None, half=False) -> Built:
    """The (r, z) section of a sphere (``r_inner = 0``) or a thick-walled sphere (0 < r_inner < r_outer), m,
    centred at the origin: a quarter (z >= 0, boundary symmetry_y at z = 0) or with ``half=True`` the whole
    meridian half-disk. Boundaries: axis, outer, inner (thick sphere), symmetry_y (quarter)."""
    if not 0 <= r_inner < r_outer:
        raise ValueError(f"sphere_section needs 0 <= r_inner < r_outer, got {r_inner}, {r_outer}")
    with _Session("sphere_section") as gmsh:
        occ = gmsh.model.occ
        shape = [(2, occ.addDisk(0, 0, 0, r_outer, r_outer))]
        if r_inner > 0:
            shape, _ = occ.cut(shape, [(2, occ.addDisk(0, 0, 0, r_inner, r_inner))])
        clip = occ.addRectangle(0, 0 if not half else -2 * r_outer, 0, 2 * r_outer, (2 if not half else 4) * r_outer)
        occ.intersect(shape, [(2, clip)])
        occ.synchronize()
        _size_field(gmsh, h, refine)
        tol = 1e-6 * r_outer

        def classify(px, py):
            rad = math.hypot(px, py)
            if r_inner > 0 and abs(rad - r_inner) < tol:
                return "inner"
            if abs(rad - r_outer) < tol:
                return "outer"
            return "axis" if abs(px) < tol else "symmetry_y"

        return _write(gmsh, path, 2, _name_curves(gmsh, classify))


@register("notched_bar", ["axis", "outer", "top", "symmetry_y"])
def notched_bar(path: Path, radius=0.5, length=2.0, notch_radius=0.1, h=0.05, refine=None, imperfection=0.0) -> Built:
    """Half of a round bar in (r, z): [0, radius] x [0, length / 2] (m), mirrored at z = 0 (boundary
    symmetry_y), with a circular notch of ``notch_radius`` (m) centred on the outer surface at z = 0 (the
    imperfection where the bar necks; 0 = a plain bar), or (``notch_radius = 0``) a smooth radius
    imperfection: r(z) = radius (1 - imperfection (1 + cos(2 pi z / length)) / 2), ``imperfection`` (1) the
    relative reduction of the radius at z = 0 (the necking bar of Simo 1988: 0.018). Boundaries: axis, outer
    (surface and notch), top, symmetry_y."""
    if not 0 <= notch_radius < radius:
        raise ValueError(f"notched_bar needs 0 <= notch_radius < radius, got {notch_radius}, {radius}")
    if not 0 <= imperfection < 0.5 or (imperfection > 0 and notch_radius > 0):
        raise ValueError(f"notched_bar: imperfection must be in [0, 0.5) and needs notch_radius = 0, got {imperfection}")
    with _Session("notched_bar") as gmsh:
        occ = gmsh.model.occ
        if imperfection > 0:
            n = 40
            zs = [length / 2 * i / n for i in range(n + 1)]
            rim = [occ.addPoint(radius * (1 - imperfection * (1 + math.cos(2 * math.pi * z / length)) / 2), z, 0)
                   for z in zs]
            p0, p1 = occ.addPoint(0, 0, 0), occ.addPoint(0, length / 2, 0)
            loop = occ.addCurveLoop([occ.addLine(p0, rim[0]), occ.addSpline(rim), occ.addLine(rim[-1], p1),
                                     occ.addLine(p1, p0)])
            shape = [(2, occ.addPlaneSurface([loop]))]
        else:
            shape = [(2, occ.addRectangle(0, 0, 0, radius, length / 2))]
        if notch_radius > 0:
            shape, _ = occ.cut(shape, [(2, occ.addDisk(radius, 0, 0, notch_radius, notch_radius))])
        occ.synchronize()
        _size_field(gmsh, h, refine)
        tol = 1e-6 * max(radius, length)

        def classify(px, py):
            if abs(px) < tol:
                return "axis"
            if abs(py) < tol:
                return "symmetry_y"
            if abs(py - length / 2) < tol:
                return "top"
            return "outer"

        return _write(gmsh, path, 2, _name_curves(gmsh, classify))
