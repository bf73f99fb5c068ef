"""Benchmark ``gmsh3d`` (issue 20, lever 5): gmsh's 3D algorithm and optimization for the 3D scenes' meshes.

The builders mesh 3D bodies with gmsh's default Delaunay (``Mesh.Algorithm3D = 1``) and then Netgen's
optimizer. This bench meshes the geometry of ball-indent, hertz-3d and hertz-force-3d (coarser with
``--quick``; a scene's own mesh keys aside) with each variant: Delaunay or HXT (``Mesh.Algorithm3D = 10``, one
thread as the builders use, or two), Netgen optimization on or off, gmsh's own optimizer at 0.6 instead of 0.3
(hertz-force-3d's mesh since session 15), and reports the meshing time, the elements and the worst and mean SICN
of the mesh (:mod:`wendel.remesh.quality`). A variant changes the mesh, hence the fingerprints of a run: measured here,
not switched on.
"""

from __future__ import annotations

import time
from pathlib import Path

from . import WORKFLOWS, register

VARIANTS = {"delaunay+netgen": (1, True, 1), "delaunay": (1, False, 1), "hxt+netgen": (10, True, 1), "hxt": (10, False, 1),
            "delaunay+netgen, 2 threads": (1, True, 2), "hxt+netgen, 2 threads": (10, True, 2),
            "delaunay, optimizer at 0.6": (1, False, 1, 0.6)}
"""Variant: (gmsh Mesh.Algorithm3D, Netgen optimization, General.NumThreads and Mesh.MaxNumThreads3D[, gmsh's own
optimizer's Mesh.OptimizeThreshold: the builders' ``optimize_threshold``, hertz-force-3d's 0.6])."""
SCENES = {"ball-indent.toml": 1.0, "hertz-3d.toml": 1.5, "hertz-force-3d.toml": 1.0}
"""Scenes and the factor on their h (hertz-3d at its default took 53 s to mesh in issue 20)."""


def mesh_with(variant: str, scene_path: Path, scale: float, out: Path) -> dict:
    """Mesh the scene's geometry with a variant; its row."""
    import gmsh

    from ..meshes import build
    from ..remesh import quality
    from ..results import vtu
    from ..scene import load

    algorithm, netgen, threads, *threshold = VARIANTS[variant]
    scene = load(scene_path)
    params = {k: v for k, v in scene.geometry.params.items() if k not in ("optimize", "algorithm", "optimize_threshold")}
    params["h"] = params.get("h", scene.geometry.h) * scale
    if isinstance(params.get("refine"), dict) and "h" in params["refine"]:
        params["refine"] = {**params["refine"], "h": params["refine"]["h"] * scale}
    generate, optimize = gmsh.model.mesh.generate, gmsh.model.mesh.optimize

    def generate_with(dim=3):
        gmsh.option.setNumber("Mesh.Algorithm3D", algorithm)
        gmsh.option.setNumber("General.NumThreads", threads)
        gmsh.option.setNumber("Mesh.MaxNumThreads3D", threads)
        if threshold:
            gmsh.option.setNumber("Mesh.OptimizeThreshold", threshold[0])
        generate(dim)

    def optimize_with(method="", *args, **kwargs):
        if netgen or method != "Netgen":
            optimize(method, *args, **kwargs)

    gmsh.model.mesh.generate, gmsh.model.mesh.optimize = generate_with, optimize_with
    try:
        t0 = time.perf_counter()
        built = build(scene.geometry.builder, out, **params)
        seconds = time.perf_counter() - t0
    finally:
        gmsh.model.mesh.generate, gmsh.model.mesh.optimize = generate, optimize
    points, cells = vtu.read_mesh(out, 3)
    q = quality.mesh_quality(points, cells)
    return {"scene": scene_path.stem, "h_factor": scale, "variant": variant, "seconds": seconds,
            "dofs": 3 * built.nodes,
            "elements": built.elements, "min_sicn": q["min"], "mean_sicn": q["mean"], "inverted": q["inverted"]}


@register("gmsh3d")
def gmsh3d(quick: bool, workdir: Path) -> list[dict]:
    """Each 3D scene's geometry meshed with each variant (coarser with --quick)."""
    rows = []
    workdir.mkdir(parents=True, exist_ok=True)
    for name, scale in SCENES.items():
        for variant in VARIANTS:
            rows.append(mesh_with(variant, WORKFLOWS / name, scale * (2.0 if quick else 1.0),
                                  workdir / f"{Path(name).stem}-{variant}.msh"))
    return rows
