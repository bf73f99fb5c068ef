"""``wendel bench cutting-levers``: where the FE cut's time goes, and levers on it measured (issue 17's 15 minutes).

The steel cut's first 200 um (40 increments of 5 um, remeshed every 8) at edge r/2 with F-bar, conduction and
MUMPS (the settled-cut benches' scene, ``direct``'s cut made longer), as the scene says (``base``), the same again
(``base again``: the loop is deterministic, its ``cutting.csv`` the same byte for byte), and once per lever:
``numerics.newton_tol = 1e-6`` (the cut's own is 1e-8; below about 1e-4 its Newton iterations converge linearly,
the heat and the Johnson-Cook softening being outside the tangent) and ``cutting.remesh_every = 16`` (half the
re-equilibrations). Rows: increments, step cuts, Newton iterations, remeshes, wall time and its phases (assembly,
linear solve, constitutive update, failed increments and failed launches, from ``summary.json``), the travel
reached and why a run stopped, the travel-weighted F_c and F_t over the last 100 um, and ``same_as_base``.
``--quick``: 40 um, the levers only."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

from . import register

LEVERS = [("base", {}), ("base again", {}), ("newton_tol 1e-6", {"newton_tol": 1e-6}),
          ("remesh_every 16", {"remesh_every": 16})]
PHASES = ("assembly", "linear_solve", "constitutive", "failed_increments", "failed_launches")


def _scene(steps: int, lever: dict):
    from .direct import cut_scene
    scene = cut_scene(steps)
    scene.numerics.direct = "mumps"
    scene.geometry.model_extra["length"] = 2.6e-3       # the settled-cut benches' block
    if "newton_tol" in lever:
        scene.numerics.newton_tol = lever["newton_tol"]
    if "remesh_every" in lever:
        scene.cutting.remesh_every = lever["remesh_every"]
    return scene


def _run(name: str, lever: dict, steps: int, out: Path) -> dict:
    from .cutting_mesh import cut, measure
    shutil.rmtree(out, ignore_errors=True)
    stopped = cut(_scene(steps, lever), out, frames=False)
    s = json.loads((out / "summary.json").read_text())
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader((out / "cutting.csv").open())]
    last = measure(rows, 100e-6)        # travel-weighted means over the last 100 um
    ph = s["wall_time_by_phase"]
    return {"case": name, "travel_um": rows[-1]["tool_travel_m"] * 1e6, "increments": s["increments"],
            "step_cuts": s["step_cuts"], "newton_iterations": s["newton_iterations"], "remeshes": len(s["remeshes"]),
            "wall_s": s["wall_time"], **{f"{p}_s": ph.get(p, 0.0) for p in PHASES},
            "Fc_last100": last["Fc_last"], "Ft_last100": last["Ft_last"], "stopped": stopped}


@register("cutting-levers")
def cutting_levers_bench(quick: bool, workdir: Path) -> list[dict]:
    """The 200 um F-bar cut with conduction as the scene says, again, and with each lever (see the module)."""
    steps = 8 if quick else 40
    rows, base = [], None
    for name, lever in LEVERS[2:] if quick else LEVERS:
        out = workdir / name.replace(" ", "-")
        rows.append(_run(name, lever, steps, out))
        got = (out / "cutting.csv").read_bytes()
        base = got if name == "base" else base          # this run's base only (not an older run's folder)
        if base is not None:
            rows[-1]["same_as_base"] = got == base
    return rows
