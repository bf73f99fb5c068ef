"""Scene key ``numerics.assembly``: the FreeFEM-language forms (default) or wendel's compiled element kernels.

``assembly = "compiled"`` (``-DWITHKERNELS=1``, ``edp/lib/kernels.idp``, plugin ``edp/plugins/wendel_kernels.cpp``)
computes the quadrature-point strain, the internal forces and the consistent J2 tangent of 3D P1 small-strain
plasticity in C++; the Newton algorithm, return mapping, contact and solver stay in the .edp scripts. Other
combinations are refused here naming the key (and once more at launch, where the mesh's dimension is known).
"""

from __future__ import annotations

ASSEMBLIES = {"freefem": "the FreeFEM-language varf forms (every scene)",
              "compiled": "compiled element kernels: 3D P1 small-strain J2 plasticity, frictionless contact or none"}


def check(scene) -> None:
    """Raise ValueError naming numerics.assembly when the scene cannot use the compiled kernels."""
    if scene.numerics.assembly != "compiled":
        return
    why = []
    if scene.problem != "mechanics" or getattr(scene, "plasticity", None) is None:
        why.append("a [plasticity] table")
    if scene.kinematics.updated_lagrangian:
        why.append("kinematics.kind = \"small-strain\"")
    if getattr(scene, "thermal", None) is not None:
        why.append("no [thermal] table")
    disc = getattr(scene, "discretization", None)
    if disc is not None and getattr(disc, "kind", "cg") != "cg":
        why.append("continuous elements")
    g = scene.geometry
    if not (g.builder == "box" or (g.builder is None and g.dimension == 3)):
        why.append("a 3D body (builder \"box\" or a 3D mesh file)")
    if getattr(scene, "drilling", None) is not None:
        why.append("no [drilling] table (not verified)")
    if scene.elasticity.order != 1:
        why.append("elasticity.order = 1")
    if scene.elasticity.plane == "axisymmetric":
        why.append("no (r, z) model")
    contact = getattr(scene, "contact", None)
    if contact is not None:
        from .blocks.contact import in_current_configuration
        if in_current_configuration(contact, scene):
            why.append("frictionless contact in the undeformed configuration")
    if why:
        raise ValueError("numerics.assembly = \"compiled\" (3D P1 small-strain J2 plasticity) needs "
                         + ", ".join(why))


def macros(scene, dimension: int) -> list[str]:
    """``-DWITHKERNELS=1`` for a compiled-assembly scene; a 2D scene is refused (ValueError)."""
    if scene.numerics.assembly != "compiled":
        return []
    if dimension != 3:
        raise ValueError("numerics.assembly = \"compiled\" is for 3D meshes (tetrahedra); this scene is 2D")
    return ["-DWITHKERNELS=1"]
