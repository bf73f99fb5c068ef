"""Axisymmetric (r, z) scenes: ``elasticity.plane = "axisymmetric"`` on a 2D mesh with x = r >= 0, y = z.

The launch adds ``-DAXISYMMETRIC=1`` to the FreeFEM command line (:func:`macros`; edp/lib/axisymmetric.idp: the
hoop strain and the 2 pi r weights), ``-DPk=P2`` for ``elasticity.order = 2`` (:func:`element`), and the options
of the closed-form references of ``elasticity.reference`` (:func:`options`; a registry: name -> options function).

>>> sorted(REFERENCES)
['heated-cylinder', 'thick-sphere']
"""

from __future__ import annotations

from typing import Callable


def _thick_sphere(scene) -> list[str]:
    """Lame's sphere (and, with perfect plasticity, its first-yield and limit pressures): pressure on
    boundary.inner, radii from the sphere_section builder."""
    g, inner = scene.geometry, scene.boundary.get("inner")
    p = g.params
    if g.builder != "sphere_section" or not p.get("r_inner") or inner is None or not inner.pressure:
        raise ValueError("elasticity.reference = 'thick-sphere' needs geometry.builder = 'sphere_section' with "
                         "r_inner > 0 and a pressure on boundary.inner")
    opts = ["-axi_sphere_p", repr(float(inner.pressure)), "-axi_sphere_a", repr(float(p["r_inner"])),
            "-axi_sphere_b", repr(float(p.get("r_outer", 1.0)))]
    plast = getattr(scene, "plasticity", None)
    if plast is not None:
        if plast.law != "perfect":
            raise ValueError("elasticity.reference = 'thick-sphere' with plasticity needs plasticity.law = 'perfect'")
        opts += ["-axi_sphere_sigma0", repr(float(plast.sigma0))]
    return opts


def _heated_cylinder(scene) -> list[str]:
    """Timoshenko-Goodier's hollow cylinder under a steady radial temperature profile (plane strain): radii
    from the hollow_cylinder_section builder; the thermal table heats it."""
    g = scene.geometry
    p = g.params
    if g.builder != "hollow_cylinder_section" or getattr(scene, "thermal", None) is None:
        raise ValueError("elasticity.reference = 'heated-cylinder' needs geometry.builder = "
                         "'hollow_cylinder_section' and a thermal table")
    return ["-axi_cyl_a", repr(float(p.get("r_inner", 1.0))), "-axi_cyl_b", repr(float(p.get("r_outer", 2.0)))]


REFERENCES: dict[str, Callable] = {"heated-cylinder": _heated_cylinder, "thick-sphere": _thick_sphere}


AXI_BUILDERS = {"axi_rectangle", "sphere_section", "hollow_cylinder_section", "notched_bar", "drilled-section"}
"""Builders of (r, z) sections; the plane 2D builders work too when their x range is >= 0 (FreeFEM checks)."""


def check(scene) -> None:
    """Rules of ``elasticity.plane/order/reference`` that join other tables, applied when the scene is read."""
    el, g = scene.elasticity, scene.geometry
    if g.builder is not None:
        from ..meshes.params import validate

        try:
            validate(g.builder, g.params)
        except ValueError:
            return                     # the geometry check names the bad keyword after this one
    if el.reference is not None:
        if el.plane != "axisymmetric":
            raise ValueError(f"elasticity.reference = {el.reference!r} needs elasticity.plane = 'axisymmetric'")
        REFERENCES[el.reference](scene)            # its own requirements (builder, loads, law)
    if el.order == 2 and (scene.blocks or scene.remesh is not None or g.builder == "box" or g.dimension == 3):
        raise ValueError("elasticity.order = 2 is for 2D elastic scenes (no plasticity, contact, thermal or remesh table)")
    if el.plane != "axisymmetric":
        if g.builder in AXI_BUILDERS:
            raise ValueError(f"geometry.builder = {g.builder!r} makes an (r, z) section: set elasticity.plane = 'axisymmetric'")
        return
    if g.builder == "box" or g.dimension == 3:
        raise ValueError("elasticity.plane = 'axisymmetric' needs a 2D (r, z) mesh")
    contact = getattr(scene, "contact", None)
    if contact is not None and contact.obstacle in ("ball", "cylinder"):
        if contact.obstacle == "cylinder" or contact.center[0] != 0 or contact.normal[1] != "y":
            raise ValueError("contact in an axisymmetric scene: a ball is a sphere only when centred on the axis "
                             "(contact.center = [0, z]) and pressed along it (contact.normal = '+y' or '-y')")
    thermal = getattr(scene, "thermal", None)
    if thermal is not None and thermal.source == "manufactured":
        raise ValueError("thermal.source = 'manufactured' is Cartesian; it has no axisymmetric form")


def element(scene, dimension: int) -> str | None:
    """``P2`` for ``elasticity.order = 2`` (2D elastic scenes without remeshing), else None (the default P1)."""
    if scene.problem != "mechanics" or scene.elasticity.order == 1:
        return None
    if dimension != 2 or scene.blocks or scene.remesh is not None:
        raise ValueError("elasticity.order = 2 is for 2D elastic scenes (no plasticity, contact, thermal "
                         "or remesh table)")
    return "P2"


def macros(scene, dimension: int) -> list[str]:
    """``-DAXISYMMETRIC=1`` for ``elasticity.plane = "axisymmetric"`` (checked: a 2D mesh, a ball on the axis)."""
    if scene.problem != "mechanics" or scene.elasticity.plane != "axisymmetric":
        return []
    if dimension != 2:
        raise ValueError(f"elasticity.plane = 'axisymmetric' needs a 2D (r, z) mesh; this one is {dimension}D")
    contact = getattr(scene, "contact", None)
    if contact is not None and contact.obstacle in ("ball", "cylinder"):
        if contact.obstacle == "cylinder" or contact.center[0] != 0 or contact.normal[1] != "y":
            raise ValueError("contact in an axisymmetric scene: a ball is a sphere only when centred on the axis "
                             "(contact.center = [0, z]) and pressed along it (contact.normal = '+y' or '-y')")
    return ["-DAXISYMMETRIC=1"]


def options(scene, dimension: int) -> list[str]:
    """FreeFEM ``-key value`` options of the closed-form reference ``elasticity.reference`` (run-time values)."""
    el = scene.elasticity
    if el.reference is None:
        return []
    if el.plane != "axisymmetric":
        raise ValueError(f"elasticity.reference = {el.reference!r} needs elasticity.plane = 'axisymmetric'")
    return REFERENCES[el.reference](scene)
