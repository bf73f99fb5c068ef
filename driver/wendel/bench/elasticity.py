"""Benchmark ``elasticity``: the smoke problem at growing sizes, direct solver against ffddm on 1 and 2 ranks."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from . import WORKFLOWS, register


@register("elasticity")
def elasticity(quick: bool, workdir: Path) -> list[dict]:
    """The smoke problem at growing sizes: direct solver vs ffddm on 1 and 2 ranks; start-up share."""
    sizes = [0.05, 0.025] if quick else [0.05, 0.025, 0.0125, 0.00625]
    rows = []
    for h in sizes:
        for solver, ranks in (("direct", 1), ("ffddm", 1), ("ffddm", 2)):
            tag = f"h{h:g}-{solver}-np{ranks}"
            shutil.rmtree(workdir / tag, ignore_errors=True)
            s = _run_with(WORKFLOWS / "smoke.toml", workdir / tag, h=h, solver=solver, ranks=ranks)
            ph = s["wall_time_by_phase"]
            rows.append({"h": h, "dofs": s["dofs"], "solver": solver, "ranks": ranks,
                         "wall_time": s["wall_time"], "assembly": ph["assembly"], "linear_solve": ph["linear_solve"],
                         "startup": ph["freefem_startup"], "io": ph["freefem_output"] + ph["driver_output"],
                         "share_startup_io": s["share_startup_and_io"],
                         "linear_iterations": s["last_increment"]["linear_iterations"]})
    return rows


def _run_with(scene_path: Path, workdir: Path, h: float, solver: str, ranks: int) -> dict:
    """Run a scene with a given size, solver and rank count (no picture)."""
    from .. import loop as runmod
    from ..scene import load

    scene = load(scene_path)
    scene.geometry.h = h
    scene.numerics.solver = solver
    scene.numerics.ranks = ranks
    scene.output.png = False
    root = runmod.run_scene(scene, scene_path, workdir, progress=lambda *_: None)
    return json.loads((root / "summary.json").read_text())
