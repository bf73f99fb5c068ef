"""``wendel bench cutting-levers``: where the FE cut's time goes, and levers on it measured (issue 17's 15 minutes).

The steel cut's first 200 um (40 increments of 5 um, remeshed every 8) at edge r/2 with F-bar, conduction and
MUMPS (the settled-cut benches' scene, ``direct``'s cut made longer), as the scene says (``base``), the same again
(``base again``: the loop is deterministic, its ``cutting.csv`` the same byte for byte), and once per lever:
``numerics.newton_tol = 1e-6`` (the cut's own is 1e-8), ``cutting.remesh_every = 16`` (half the
re-equilibrations), ``cutting.first_step = 0.0625`` (a sixteenth of the step first on a new mesh, not a quarter)
and steps of 10 um remeshed every 4 (the same travel between remeshes); session 25's lever taken back
(``lagged softening``: ``thermal.staggered_softening = false``,
the mechanical step blind to its heat step's Johnson-Cook softening: Newton linear below 1e-3, about 0.13-0.19 an
iteration); session 24's two levers taken back one at a time and together with it (``cutting.relax_tol = 1e-8``:
each stage of a re-equilibration converged; ``cutting.first_step = 1``: the whole first step on a new mesh), and,
as a diagnostic, the cut without heat (``thermal.beta = 0``, adiabatic: no plastic or frictional heat). Rows:
increments, step cuts, Newton iterations (of the increments accepted, of the re-equilibrations among them, and of
the failed tries), remeshes, wall time and its phases (assembly, linear solve, constitutive update, failed
increments and failed launches, from ``summary.json``), the median ratio of successive relative residuals below
1e-3 (``tail_ratio``: about 0.1 is a linear tail, 1e-3 and less quadratic), the travel reached and why a run
stopped, the travel-weighted F_c and F_t over the last 100 um, and ``same_as_base``. ``--quick``: 40 um, the
levers only."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

from . import register

BEFORE = {"25": {"soft": False},                                        # before session 25's softening
          "24": {"relax_tol": 1e-8, "first_step": 1.0, "soft": False}}   # before session 24's two levers too
LEVERS = [("base", {}), ("base again", {}), ("newton_tol 1e-6", {"newton_tol": 1e-6}),
          ("remesh_every 16", {"remesh_every": 16}), ("stages converged", {"relax_tol": 1e-8}),
          ("whole first step", {"first_step": 1.0}), ("lagged softening", BEFORE["25"]),
          ("before session 24", BEFORE["24"]), ("no heat", {"heat": False}),
          ("sixteenth first step", {"first_step": 0.0625}), ("10 um steps", {"step_um": 10, "remesh_every": 4})]
PHASES = ("assembly", "linear_solve", "constitutive", "failed_increments", "failed_launches")


def _scene(steps: int, lever: dict):
    from .direct import cut_scene
    scene = cut_scene(steps)
    scene.numerics.direct = "mumps"
    scene.geometry.model_extra["length"] = 2.6e-3       # the settled-cut benches' block
    if "newton_tol" in lever:
        scene.numerics.newton_tol = lever["newton_tol"]
    for key in ("remesh_every", "relax_tol", "first_step"):
        if key in lever:
            setattr(scene.cutting, key, lever[key])
    if "soft" in lever:             # the staggered step without the heat step's softening (before session 25)
        scene.thermal.staggered_softening = lever["soft"]
    if "step_um" in lever:          # the same travel in steps of that length [um]
        scene.loading.steps = round(scene.cutting.cut_length / (lever["step_um"] * 1e-6))
    if "perturb" in lever:          # another round-off of the tool path (cutting-paths)
        scene.cutting.cut_length *= 1 + lever["perturb"] * 1e-13
    if lever.get("heat") is False:
        scene.thermal.beta, scene.thermal.coupling = 0.0, "adiabatic"
    return scene


def _newton(out: Path, summary: dict) -> dict:
    """Newton iterations of the failed tries and of the re-equilibrations (the remesh reports in ``summary``), and
    the tail ratio (see the module)."""
    import numpy as np
    failed = sum(len(f.read_text().splitlines()) - 2 for f in (out / "failed-attempts").glob("*-newton.csv"))
    reeq = sum(r.get("reequilibration_iterations", 0) for r in summary["remeshes"])
    runs: dict = {}
    for r in csv.DictReader((out / "newton.csv").open()):
        runs.setdefault((r["increment"], r["load_factor"]), []).append(float(r["relative_residual"]))
    ratios = [b / a for v in runs.values() for a, b in zip(v[1:], v[2:]) if 0 < a < 1e-3 and 0 < b]
    return {"reequilibration_newton": reeq, "failed_newton": failed,
            "tail_ratio": float(np.median(ratios)) if ratios else float("nan")}


def _run(name: str, lever: dict, steps: int, out: Path) -> dict:
    from .cutting_mesh import cut, measure
    shutil.rmtree(out, ignore_errors=True)
    stopped = cut(_scene(steps, lever), out, frames=False)
    s = json.loads((out / "summary.json").read_text())
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader((out / "cutting.csv").open())]
    last = measure(rows, 100e-6)        # travel-weighted means over the last 100 um
    ph = s["wall_time_by_phase"]
    return {"case": name, "travel_um": rows[-1]["tool_travel_m"] * 1e6, "increments": s["increments"],
            "step_cuts": s["step_cuts"], "newton_iterations": s["newton_iterations"], **_newton(out, s),
            "remeshes": len(s["remeshes"]),
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


@register("cutting-paths")
def cutting_paths_bench(quick: bool, workdir: Path) -> list[dict]:
    """The 200 um cut of ``cutting-levers`` as the scene says (``new``) and as before session 25 (``before``:
    ``thermal.staggered_softening = false``; ``WENDEL_BENCH_BEFORE=24``: as before session 24, also
    ``cutting.relax_tol = 1e-8``, ``cutting.first_step = 1``) on ``WENDEL_BENCH_PATHS`` (default 4) tool paths that
    differ in their 13th digit (``cutting.cut_length`` times 1 + k 1e-13, k = 1, 2, ...): the cut's Newton path is
    chaotic (a path that differed in its last digit took 117 step cuts instead of 190 over 1.2 mm), so a lever
    is judged over several paths, new and before interleaved. ``WENDEL_BENCH_LEVER``: against one of
    ``cutting-levers``' levers instead (its name with hyphens, e.g. ``sixteenth-first-step``). ``--quick``: 2 paths
    of 40 um (no remesh in them: a check of the bench, not of the levers)."""
    import os
    n = os.environ.get("WENDEL_BENCH_PATHS", "4")
    if not (n.isdigit() and 1 <= int(n) <= 20):
        raise ValueError(f"WENDEL_BENCH_PATHS = {n!r}: a whole number of paths from 1 to 20")
    since = os.environ.get("WENDEL_BENCH_BEFORE", "25")
    if since not in BEFORE:
        raise ValueError(f"WENDEL_BENCH_BEFORE = {since!r}: one of {', '.join(sorted(BEFORE))} "
                         f"(the loop before that session)")
    against = ("before", BEFORE[since])
    named = {name.replace(" ", "-"): lever for name, lever in LEVERS[2:]}
    if "WENDEL_BENCH_LEVER" in os.environ:
        name = os.environ["WENDEL_BENCH_LEVER"]
        if name not in named:
            raise ValueError(f"WENDEL_BENCH_LEVER = {name!r}: one of {', '.join(named)} (cutting-levers' levers)")
        against = (name, named[name])
    steps, rows = 8 if quick else 40, []
    for k in range(1, (2 if quick else int(n)) + 1):
        for name, lever in (("new", {}), against):
            rows.append({"path": k, **_run(name, {**lever, "perturb": k}, steps, workdir / f"{name}-{k}")})
    return rows
