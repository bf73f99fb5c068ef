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

import numpy as np

from . import WORKFLOWS, register

LEVERS = [("base", {}), ("base again", {}), ("newton_tol 1e-6", {"newton_tol": 1e-6}),
          ("remesh_every 16", {"remesh_every": 16})]
PHASES = ("assembly", "linear_solve", "constitutive", "failed_increments", "failed_launches")


def _scene(steps: int, lever: dict):
    from .cutting_mesh import _scene as steel
    scene = steel(2, 1, quick=False, vol="fbar")
    scene.thermal.coupling = "staggered"
    scene.numerics.direct = "mumps"
    scene.geometry.model_extra["length"] = 2.6e-3       # the settled-cut benches' block
    scene.cutting.cut_length = steps * 5e-6
    scene.loading.steps = steps
    if "newton_tol" in lever:
        scene.numerics.newton_tol = lever["newton_tol"]
    if "remesh_every" in lever:
        scene.cutting.remesh_every = lever["remesh_every"]
    return scene


def _run(name: str, lever: dict, steps: int, out: Path) -> dict:
    from ..cutting.fe_run import run_cut
    from ..errors import StepCutError
    from ..freefem import FreeFemError, NewtonFailure
    shutil.rmtree(out, ignore_errors=True)
    stopped = ""
    try:
        run_cut(_scene(steps, lever), WORKFLOWS / "cutting-aisi1045.toml", out, smoke=False,
                progress=lambda *_: None, frames=False)
    except (NewtonFailure, StepCutError, FreeFemError) as exc:
        stopped = str(exc).split(";")[0]
    s = json.loads((out / "summary.json").read_text())
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader((out / "cutting.csv").open())]
    t = np.array([r["tool_travel_m"] for r in rows])
    w = np.diff(t, prepend=0.0)
    last = (t > t[-1] - 100e-6 + 1e-12) & (w > 1e-12)
    ph = s["wall_time_by_phase"]
    return {"case": name, "travel_um": t[-1] * 1e6, "increments": s["increments"], "step_cuts": s["step_cuts"],
            "newton_iterations": s["newton_iterations"], "remeshes": len(s["remeshes"]), "wall_s": s["wall_time"],
            **{f"{p}_s": ph.get(p, 0.0) for p in PHASES},
            "Fc_last100": float(np.average([r["Fc_N"] for r, k in zip(rows, last) if k], weights=w[last])),
            "Ft_last100": float(np.average([r["Ft_N"] for r, k in zip(rows, last) if k], weights=w[last])),
            "stopped": stopped}


@register("cutting-levers")
def cutting_levers_bench(quick: bool, workdir: Path) -> list[dict]:
    """The 200 um F-bar cut with conduction as the scene says, again, and with each lever (see the module)."""
    steps = 8 if quick else 40
    rows = []
    for name, lever in LEVERS[2:] if quick else LEVERS:
        out = workdir / name.replace(" ", "-")
        rows.append(_run(name, lever, steps, out))
        base = workdir / "base" / "cutting.csv"
        if base.is_file():
            rows[-1]["same_as_base"] = (out / "cutting.csv").read_bytes() == base.read_bytes()
    return rows
