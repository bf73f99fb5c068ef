"""Benchmark ``thermal``: cost of the coupled (u, T) solve against the mechanical-only one on the same mesh.

The manufactured thermoelastic scene (workflows/thermo-mms.toml) runs monolithic and staggered, and the
same scene without its ``[thermal]`` block (workflows/smoke-mms.toml: same geometry, material and
mesh) runs as the mechanical reference; rows give wall times by phase and their ratios.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from . import WORKFLOWS, register


@register("thermal")
def thermal(quick: bool, workdir: Path) -> list[dict]:
    """Mechanics alone, monolithic and staggered coupling, at growing sizes."""
    from .. import loop as runmod
    from ..scene import load

    sizes = [0.1, 0.05] if quick else [0.1, 0.05, 0.025, 0.0125]
    rows = []
    for h in sizes:
        base = None
        for case, scene_file, coupling in (("mechanics", "smoke-mms.toml", None),
                                           ("monolithic", "thermo-mms.toml", "monolithic"),
                                           ("staggered", "thermo-mms.toml", "staggered")):
            tag = f"h{h:g}-{case}"
            shutil.rmtree(workdir / tag, ignore_errors=True)
            scene = load(WORKFLOWS / scene_file)
            scene.geometry.h = h
            scene.output.png = False
            if coupling:
                scene.thermal.coupling = coupling
            root = runmod.run_scene(scene, WORKFLOWS / scene_file, workdir / tag, progress=lambda *_: None)
            s = json.loads((root / "summary.json").read_text())
            ph = s["wall_time_by_phase"]
            solve = ph["assembly"] + ph["linear_solve"] + ph["constitutive"]
            base = base or solve
            rows.append({"h": h, "case": case, "dofs": s["dofs"], "newton_iterations": s["newton_iterations"],
                         "assembly": ph["assembly"], "linear_solve": ph["linear_solve"], "solve": solve,
                         "wall_time": s["wall_time"], "solve_vs_mechanics": solve / base})
    return rows

