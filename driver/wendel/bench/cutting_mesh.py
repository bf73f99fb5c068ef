"""``wendel bench cutting-mesh``: mesh and step convergence of the FE cut's forces (issue 17).

The steel scene ``workflows/cutting-aisi1045.toml`` is cut with the graded remesh (``cutting.edge_size``,
:func:`wendel.cutting.fe.size_zones`) at three edge resolutions, the edge radius r = 20 um over 2, 3 and 4
(10, 6.7 and 5 um at the edge, the rest of the mesh the same; at r/1, 20 um, the first re-equilibration did not
converge, measured), and once more at r/2 with half the increment (2.5 um, remeshed every twice as many increments: the same 40 um of travel between remeshes).
Each cuts the first 400 um (2.7 h) of the scene's 600 um (``STEPS``); ``--quick`` the first 100 um.

A remeshed cut is a saw-tooth (the force drops in each re-equilibration and recovers over the cycle), so each
case is measured over the same **window of travel**, the last ``WINDOW`` (160 um, 4 remesh cycles): ``*_last``
is the mean over its increments weighted by the travel each covers (re-equilibrations excluded: for a force,
the work over the travel), ``*_spread`` the spread (max - min) / mean of the remesh-cycle means
(:func:`wendel.cutting.fe_steady.cycle_means`) inside it, ``*_inc_spread`` that of the single increments. ``dFc_*`` compare the case with the finest
edge at the same step and with the same edge at the other step: ``(F_c - F_c_ref) / F_c_ref``.

``cutting-steady``: r/2 cut 1.2 mm on a longer block: do the remesh-cycle means settle; ``cutting-fbar``: r/2 with F-bar
(``cutting.volumetric = "fbar"``) against the same without it; ``cutting-steady-fbar``: ``cutting-steady`` with F-bar. Each
case is written to ``results/bench/work/cutting-mesh/<case>/``; a folder holding the finished cut of the same scene
(``cutting.csv``, ``summary.json``, that ``scene.resolved.json``) is read, not run again (8-25 minutes a case)."""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path

import numpy as np

from . import WORKFLOWS, cut_mm, edge, edges, env_flag, heat, register, volumetric

WINDOW = 160e-6  # m: the compared window, the last 160 um of travel (4 remesh cycles of 40 um without step cuts)
STEPS = 80       # increments of 5 um: the first 400 um (2.7 h) of the scene's 600 um cut
CASES = [("r/2", 2, 1), ("r/4", 4, 1), ("r/3", 3, 1), ("r/2, half step", 2, 2)]  # name, r / edge size, increments per 5 um


def _scene(divide: int, substeps: int, quick: bool, vol: str | None = None):
    """The steel scene at edge r / ``divide``, ``substeps`` increments per 5 um, ``cutting.volumetric`` ``vol`` or its own."""
    from ..scene import load
    scene = load(WORKFLOWS / "cutting-aisi1045.toml")
    c = scene.cutting
    c.volumetric = vol or c.volumetric
    steps = 20 if quick else STEPS
    c.cut_length *= steps / scene.loading.steps
    scene.loading.steps = steps
    c.edge_size = c.edge_radius / divide
    scene.loading.steps *= substeps
    c.remesh_every *= substeps
    return scene


def _finished(out: Path, scene) -> bool:
    from ..cutting.fe import fe_scene
    try:
        old = json.loads((out / "scene.resolved.json").read_text())
        new = json.loads(fe_scene(scene).model_dump_json())
        done = json.loads((out / "summary.json").read_text()).get("increments", 0) > 0
    except (OSError, ValueError):
        return False
    return done and (out / "cutting.csv").is_file() and _same(old, new)


def _same(a, b) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return all(_same(a.get(k), b.get(k)) for k in set(a) & set(b))
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return abs(a - b) <= 1e-9 * max(abs(a), abs(b), 1e-30)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a == b


def measure(rows: list[dict], window: float = WINDOW) -> dict:
    """The last ``window`` [m] of travel of a cut's ``cutting.csv`` rows (see the module)."""
    from ..cutting.fe_steady import SERIES, cycle_means
    t = np.array([r["tool_travel_m"] for r in rows])
    hi, lo = t[-1], t[-1] - window
    w = np.diff(t, prepend=0.0)                     # the travel each row covers (0 for a re-equilibration)
    inc = (t > lo + 1e-12) & (w > 1e-12)
    cyc = [c for c in cycle_means(rows) if c["tool_travel_m"] > lo]
    out = {"window_from_um": float(lo) * 1e6, "window_to_um": float(hi) * 1e6, "cycles": len(cyc)}
    for key, name in zip(SERIES, ("Fc", "Ft", "chip")):
        scale = 1e6 if key == "chip_thickness_m" else 1.0
        v = np.array([r[key] for r in rows], dtype=float)
        ok = inc & np.isfinite(v)
        c = np.array([r[key] for r in cyc], dtype=float)
        out[f"{name}_last"] = float(np.average(v[ok], weights=w[ok])) * scale if ok.any() else float("nan")
        out[f"{name}_spread"] = float(np.ptp(c) / abs(c.mean())) if len(c) > 1 else float("nan")
        out[f"{name}_inc_spread"] = float(np.ptp(v[ok]) / abs(v[ok].mean())) if ok.sum() > 1 else float("nan")
    return out


def sawtooth(out: Path) -> dict:
    """What each re-equilibration of the run in ``out`` does: the change of F_c over it (relative, the least
    and the most) and the cells' mean stress extremes [MPa] before it (the end of a cycle) and after it (the
    transferred state re-equilibrated), from ``history.csv``: the checkerboard of the P1 pressure and its reset."""
    import csv
    rows = list(csv.DictReader((out / "history.csv").open()))
    drop, before, after = [], [], []
    for k, r in enumerate(rows):
        if k and r.get("reequilibration") == "1":
            a = rows[k - 1]
            drop.append(float(r["contact_force_x"]) / float(a["contact_force_x"]) - 1)
            before.append(max(-float(a["mean_stress_min"]), float(a["mean_stress_max"])))
            after.append(max(-float(r["mean_stress_min"]), float(r["mean_stress_max"])))
    if not drop:
        return {}
    return {"reeq_dFc_min": min(drop), "reeq_dFc_max": max(drop), "mean_stress_abs_before_min": min(before),
            "mean_stress_abs_before_max": max(before), "mean_stress_abs_after_min": min(after),
            "mean_stress_abs_after_max": max(after)}


def cut(scene, out: Path, frames: bool) -> str:
    """The steel scene's FE cut ``scene`` into ``out``; why it stopped (its message to the first ";"), "" if it ran
    through. Its accepted increments are reported either way (``cutting.csv``)."""
    from ..cutting.fe_run import run_cut
    from ..errors import StepCutError
    from ..freefem import FreeFemError, NewtonFailure
    try:
        run_cut(scene, WORKFLOWS / "cutting-aisi1045.toml", out, smoke=False, progress=lambda *_: None, frames=frames)
    except (NewtonFailure, StepCutError, FreeFemError) as exc:
        return str(exc).split(";")[0]
    return ""


def _case(name: str, divide: int, substeps: int, quick: bool, workdir: Path, vol: str | None = None) -> dict:
    import csv

    scene = _scene(divide, substeps, quick, vol)
    name += heat(scene)         # WENDEL_BENCH_HEAT
    out = workdir / name.replace("/", "").replace(", ", "-").replace(" ", "-")
    stopped, wall = "", float("nan")
    if _finished(out, scene):
        wall = json.loads((out / "bench-case.json").read_text()).get("wall_s", wall) \
            if (out / "bench-case.json").is_file() else wall
    else:
        shutil.rmtree(out, ignore_errors=True)
        t0 = time.perf_counter()
        stopped = cut(scene, out, frames=False)
        wall = time.perf_counter() - t0
        (out / "bench-case.json").write_text(json.dumps({"wall_s": wall, "stopped": stopped}))
    if (out / "bench-case.json").is_file():
        stopped = json.loads((out / "bench-case.json").read_text()).get("stopped", stopped)
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader((out / "cutting.csv").open())]
    s = json.loads((out / "summary.json").read_text())
    remesh = sum(r.get("remesh_seconds", 0) + r.get("transfer_seconds", 0) for r in s["remeshes"])
    c = scene.cutting
    return {"case": name, "volumetric": c.volumetric, "edge_size_um": c.edge_size * 1e6, "step_um": c.cut_length / scene.loading.steps * 1e6,
            "travel_um": rows[-1]["tool_travel_m"] * 1e6, "increments": s["increments"],
            "elements_max": int(max(r["elements"] for r in rows)), "remeshes": len(s["remeshes"]),
            "newton_iterations": s["newton_iterations"], **measure(rows), **sawtooth(out), "wall_s": wall,
            "remesh_share": remesh / wall if wall == wall else float("nan"), "stopped": stopped}


@register("cutting-mesh")
def cutting_mesh_bench(quick: bool, workdir: Path) -> list[dict]:
    """Three edge resolutions and two steps of the steel cut (see the module; 50-60 minutes, quick 10); F-bar:
    ``WENDEL_BENCH_FBAR=1`` (folders ``...-F-bar``), heat: ``WENDEL_BENCH_HEAT``, edges: ``WENDEL_BENCH_EDGES``."""
    from ..cutting.scene import predict
    workdir.mkdir(parents=True, exist_ok=True)
    vol = volumetric(_scene(2, 1, quick).cutting.volumetric)
    rows = []
    for name, divide, substeps in edges(CASES):
        rows.append(_case(name + (", F-bar" if vol == "fbar" else ""), divide, substeps, quick, workdir, vol))
        (workdir / "partial.json").write_text(json.dumps(rows, indent=1))     # a long bench that stops keeps its cases
    by = {(r["edge_size_um"], r["step_um"]): r for r in rows}
    finest = min(r["edge_size_um"] for r in rows)
    for r in rows:
        ref = by.get((finest, r["step_um"]))
        r["dFc_vs_finest_edge"] = (r["Fc_last"] - ref["Fc_last"]) / ref["Fc_last"] if ref else float("nan")
        other = [o for o in rows if o["edge_size_um"] == r["edge_size_um"] and o["step_um"] != r["step_um"]]
        r["dFc_vs_other_step"] = (r["Fc_last"] - other[0]["Fc_last"]) / other[0]["Fc_last"] if other else float("nan")
    ox = predict(_scene(1, 1, quick))
    rows.append({"case": "Oxley (sharp tool)", "Fc_last": ox.Fc, "Ft_last": ox.Ft, "chip_last": ox.chip_thickness * 1e6})
    return rows


@register("cutting-fbar")
def cutting_fbar_bench(quick: bool, workdir: Path) -> list[dict]:
    """The middle resolution of ``cutting-mesh`` (edge r/2) with F-bar (``cutting.volumetric = "fbar"``) beside
    the same case without it (each in this bench's own folder)."""
    workdir.mkdir(parents=True, exist_ok=True)
    rows = [_case("r/2", 2, 1, quick, workdir, "cell"), _case("r/2, F-bar", 2, 1, quick, workdir, "fbar")]
    rows[1]["dFc_vs_cell"] = (rows[1]["Fc_last"] - rows[0]["Fc_last"]) / rows[0]["Fc_last"]
    return rows


@register("cutting-steady")
def cutting_steady_bench(quick: bool, workdir: Path) -> list[dict]:
    """The middle resolution (edge r/2) cut twice as far as the scene, 1.2 mm (8 h), on a block 2.6 mm long
    (the primary zone stays clear of its far end): whether and where the forces and the chip settle within 2 %
    (:func:`wendel.cutting.fe_steady.steady` on the remesh-cycle means, a window of one h), with the last
    window's spreads and drifts, and where the running means over one h settle (``filtered``). ``--quick``:
    400 um. ``WENDEL_BENCH_SNAP=1`` (also for ``cutting-steady-fbar`` and ``cutting-long``): with
    ``cutting.snap_to_tool`` (folder ``...-snap``); ``WENDEL_BENCH_CONDUCTION=1``: with heat conduction and
    frictional heat (``thermal.coupling = "staggered"``, as ``cutting-heat``; folder ``...-conduction``);
    ``WENDEL_BENCH_EDGE``: the edge size r / that whole number (2-8; folder ``r<n>-...``) instead of r/2;
    ``WENDEL_BENCH_MUMPS=1``: MUMPS as the direct solver (``numerics.direct``; folder ``...-mumps``);
    ``WENDEL_BENCH_UNTIL_STEADY=1``: the cut ends at its steady state (``cutting.stop_when_steady``, ``...-until-steady``)."""
    return _steady(quick, workdir, "cell")


@register("cutting-steady-fbar")
def cutting_steady_fbar_bench(quick: bool, workdir: Path) -> list[dict]:
    """``cutting-steady`` with F-bar (``cutting.volumetric = "fbar"``): the same 1.2 mm cut at edge r/2, its
    own folder and rows (an hour or more on one core; ``--quick``: 400 um; the other settings as ``cutting-steady``).
    ``WENDEL_BENCH_REMESH_EVERY``: remesh after that many increments instead of the scene's 8 (folder ``r2-long-remeshN``);
    ``WENDEL_BENCH_CUT_MM``: a longer cut [mm] on a block 1.4 mm longer, as ``cutting-long`` (folder
    ``r2-fbar-<um>um[-remeshN]``, with ``cutting-long``'s means over each 150 um and the last 1.5 mm)."""
    import os
    every = os.environ.get("WENDEL_BENCH_REMESH_EVERY")
    if every is not None and not (every.isdigit() and 1 <= int(every) <= 100):
        raise ValueError(f"WENDEL_BENCH_REMESH_EVERY = {every!r}: a whole number of increments from 1 to 100")
    every = int(every) if every else None
    if "WENDEL_BENCH_CUT_MM" not in os.environ:
        return _steady(quick, workdir, "fbar", remesh_every=every)
    mm = cut_mm()
    return _steady(quick, workdir, "fbar", remesh_every=every, length=mm * 1e-3, block=(mm + 1.4) * 1e-3,
                   folder=f"r2-fbar-{mm * 1e3:.0f}um" + (f"-remesh{every}" if every else ""))


@register("cutting-long")
def cutting_long_bench(quick: bool, workdir: Path) -> list[dict]:
    """``cutting-steady`` cut twice as far, 2.4 mm (16 h) on a block 3.8 mm long (about 25 minutes on one core):
    whether the forces settle after the 1.2 mm, with the means over each 150 um of travel (``bin`` rows) and
    over the last 1.5 mm (``mean_*`` in the last row). ``WENDEL_BENCH_CUT_MM``: another length [mm] (the block 1.4 mm
    longer, its own folder). ``--quick``: the 400 um of ``cutting-steady --quick``."""
    mm = cut_mm()
    return _steady(quick, workdir, "cell", length=mm * 1e-3, block=(mm + 1.4) * 1e-3, folder=f"r2-{mm * 1e3:.0f}um")


def _steady(quick: bool, workdir: Path, vol: str, remesh_every: int | None = None,
            length: float = 1.2e-3, block: float = 2.6e-3, folder: str | None = None, reuse: bool = False) -> list[dict]:
    """The 1.2 mm cut of ``cutting-steady`` (or ``length`` [m] on a block ``block`` [m] long, in ``folder``) with
    ``vol`` (and ``remesh_every`` increments between remeshes instead of the scene's 8, if given): the remesh-cycle
    means, then a row of the last window's spreads and drifts, increments, step cuts, Newton iterations, wall time
    and ``steady_at_s``, the wall time when the first steady window closed (:func:`wendel.cutting.fe_steady.reached`).
    ``reuse``: a finished cut of the same scene in the folder is read (its summary's wall time), an unfinished one refused."""
    import csv

    from ..cutting.fe_steady import reached, steady, window
    div = edge()                # WENDEL_BENCH_EDGE: the edge size r / div (folder r<div>-...), default r/2
    scene = _scene(div, 1, quick=False, vol=vol)
    folder = folder or ("r2-long" if not remesh_every else f"r2-long-remesh{remesh_every}")
    folder = folder.replace("r2", f"r{div}", 1)
    if env_flag("WENDEL_BENCH_SNAP", "cutting.snap_to_tool"):
        scene.cutting.snap_to_tool, folder = True, folder + "-snap"
    if env_flag("WENDEL_BENCH_CONDUCTION", 'thermal.coupling = "staggered"'):
        scene.thermal.coupling, folder = "staggered", folder + "-conduction"
    if env_flag("WENDEL_BENCH_MUMPS", 'numerics.direct = "mumps"'):
        scene.numerics.direct, folder = "mumps", folder + "-mumps"
    if env_flag("WENDEL_BENCH_UNTIL_STEADY", "cutting.stop_when_steady"):
        scene.cutting.stop_when_steady, folder = True, folder + "-until-steady"
    long = length > 1.2e-3
    length = 0.4e-3 if quick else length
    scene.geometry.model_extra["length"] = block
    scene.cutting.cut_length = length
    scene.loading.steps = round(length / 5e-6)
    if remesh_every:
        scene.cutting.remesh_every = remesh_every
    out = workdir / folder
    reused = reuse and _finished(out, scene)
    if reuse and not reused and out.exists():       # not deleted: it may be another process's cut in progress
        raise RuntimeError(f"{out} holds an unfinished cut (running elsewhere?): let it finish, or delete the folder")
    if not reuse:                                   # (with reuse there is nothing to delete by now)
        shutil.rmtree(out, ignore_errors=True)
    t0 = time.perf_counter()
    stopped = "" if reused else cut(scene, out, frames=True)
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader((out / "cutting.csv").open())]
    s = json.loads((out / "summary.json").read_text()) if (out / "summary.json").is_file() else {}
    wall = s.get("wall_time", float("nan")) if reused else time.perf_counter() - t0
    stopped = stopped or ("" if s.get("completed", True) else "stopped before the end (summary.json)")
    st = steady(rows, scene.cutting.uncut_thickness)
    res = []
    for c in st["cycle_means"]:
        res.append({"travel_um": c["tool_travel_m"] * 1e6, "Fc_N": c["Fc_N"], "Ft_N": c["Ft_N"],
                    "chip_um": c["chip_thickness_m"] * 1e6})
    found = st["cycles"]
    means = {}
    if long and not quick:      # the means over each 150 um of travel and over the last 1.5 mm (work over travel)
        t = np.array([r["tool_travel_m"] for r in rows])
        for lo in np.arange(0.0, t[-1] - 1e-12, 150e-6):
            w = window([r for r in rows if r["tool_travel_m"] <= lo + 150e-6 + 1e-12], 150e-6)
            res.append({"travel_um": (lo + 75e-6) * 1e6, "bin": True, "Fc_N": w["steady_Fc_N"],
                        "Ft_N": w["steady_Ft_N"], "chip_um": w["steady_chip_m"] * 1e6})
        w = window(rows, 1.5e-3)
        means = {"mean_from_um": w["steady_window_from_m"] * 1e6, "mean_Fc_N": w["steady_Fc_N"],
                 "mean_Ft_N": w["steady_Ft_N"], "mean_chip_um": w["steady_chip_m"] * 1e6}
    filt = st["filtered"]
    res.append({"travel_um": rows[-1]["tool_travel_m"] * 1e6, "steady_from_um": found["start_m"] * 1e6 if found else None,
                "steady_at_s": reached(out, rows, found),
                "filtered_from_um": filt["start_m"] * 1e6 if filt else None, **means,
                **{f"fspread_{k}": v for k, v in st["last_window_spreads"]["filtered"].items()},
                **{f"spread_{k}": v for k, v in st["last_window_spreads"]["cycles"].items()},
                **{f"drift_{k}": v for k, v in st["last_window_trends"]["cycles"].items()},
                **{f"inc_spread_{k}": v for k, v in st["last_window_spreads"]["raw"].items()},
                "volumetric": vol, "increments": s.get("increments"), "step_cuts": s.get("step_cuts"),
                "newton_iterations": s.get("newton_iterations"), "remeshes": len(s.get("remeshes", [])),
                "wall_s": wall, "stopped": stopped})
    return res
