"""Benchmark ``cylinder``: cost of the plastic Newton loop of Hill's cylinder (workflows/cylinder.toml).

At 3 element sizes, one row per load increment: Newton iterations, FreeFEM wall time of the increment and
the shares of constitutive update (return mapping and consistent tangent at the quadrature points),
assembly and linear solve in it, from the cumulative ``time_*`` of each increment's record.json.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from . import WORKFLOWS, register

PHASES = ("constitutive", "assembly", "solve", "output")


def increment_costs(fem: Path) -> list[dict]:
    """Per-increment times from the cumulative record times of one run's fem/ folder.

    Times restart at zero with each FreeFEM launch: a record whose total is below the previous one
    starts a launch and is its own increment cost.
    """
    rows, prev = [], None
    for d in sorted(fem.glob("inc-*")):
        if not (d / "done").is_file():
            continue
        r = json.loads((d / "record.json").read_text())
        cur = {k: r[f"time_{k}"] for k in PHASES + ("total",)}
        if prev is not None and cur["total"] >= prev["total"]:
            inc = {k: cur[k] - prev[k] for k in cur}
        else:
            inc = dict(cur)
        prev = cur
        rows.append({"increment": r["increment"], "load_factor": r["load_factor"],
                     "newton_iterations": r["newton_iterations"], **inc})
    return rows


@register("cylinder")
def cylinder(quick: bool, workdir: Path) -> list[dict]:
    """Hill's cylinder at 3 sizes: Newton iterations, time per increment, shares of the solve phases."""
    from .. import loop as runmod
    from ..scene import load

    sizes = [0.05, 0.025, 0.0125] if quick else [0.04, 0.02, 0.01]
    rows = []
    for h in sizes:
        tag = f"h{h:g}"
        shutil.rmtree(workdir / tag, ignore_errors=True)
        scene = load(WORKFLOWS / "cylinder.toml")
        scene.geometry.h = h
        scene.output.png = False
        root = runmod.run_scene(scene, WORKFLOWS / "cylinder.toml", workdir / tag, progress=lambda *_: None)
        s = json.loads((root / "summary.json").read_text())
        for r in increment_costs(root / "fem"):
            work = r["constitutive"] + r["assembly"] + r["solve"]
            rows.append({"h": h, "dofs": s["dofs"], "increment": r["increment"], "load_factor": r["load_factor"],
                         "newton_iterations": r["newton_iterations"], "freefem_time": r["total"],
                         "time_per_newton": r["total"] / max(r["newton_iterations"], 1),
                         "share_constitutive": r["constitutive"] / work if work else 0.0,
                         "share_assembly": r["assembly"] / work if work else 0.0,
                         "share_linear_solve": r["solve"] / work if work else 0.0,
                         "share_output": r["output"] / r["total"] if r["total"] else 0.0,
                         "error_plastic_radius": s["last_increment"].get("error_plastic_radius")})
    return rows
