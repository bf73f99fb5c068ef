"""``wendel bench cutting-heat``: the FE cut with heat conduction and frictional heat against the adiabatic cut.

The steel scene ``workflows/cutting-aisi1045.toml`` on the graded mesh at edge size r/2 (10 um, the
``cutting-mesh`` bench's r/2 case), cut 400 um (``--quick``: 100 um), twice on the same meshes: as written
(``thermal.coupling = "adiabatic"``: Taylor-Quinney heat stays where it is made, no frictional heat) and with
the heat equation (``thermal.coupling`` = :data:`CONDUCTION`: conduction on the current body, the Taylor-Quinney
heat and ``cutting.heat_to_chip`` of the rake face's frictional work, every boundary insulated). ``--quick``
runs the monolithic coupling as well; the full bench runs both once more with k and c at :data:`PROPERTIES_T`.
The scene's ``cutting.volumetric`` (the P1 cell's own); ``WENDEL_BENCH_FBAR=1``: F-bar, 0: the cell's.

Per case: the window of the last 160 um of travel (``cutting-mesh``'s :func:`wendel.bench.cutting_mesh.measure`:
F_c, F_t and chip thickness weighted by travel, and their remesh-cycle spreads), the largest temperatures of the
primary and the secondary zone (:mod:`wendel.cutting.fe_zones`; the mean of the remesh-cycle means in the window
and the largest increment), the heat ledger at the end (Taylor-Quinney heat, frictional heat into the chip and
into the tool, stored heat, its balance), Newton iterations, increments and the wall time, beside Oxley's
forces, chip thickness, shear-plane and interface temperatures. Each case is written to
``results/bench/work/cutting-heat/<case>/`` and read, not run again, while its folder holds the finished cut of
the same scene (as ``cutting-mesh``); ``WENDEL_BENCH_CASES=adiabatic,monolithic`` runs only those cases (to split
the bench over two holds of the machine).
"""

from __future__ import annotations

import json
import os
import shutil
import time
from pathlib import Path

import numpy as np

from . import WORKFLOWS, env_flag, register, volumetric
from .cutting_mesh import WINDOW, _finished, _scene, measure

CONDUCTION = "staggered"
"""The coupling of the conducting case: monolithic and staggered gave the same forces and temperatures (to 1e-6)
and the same Newton iterations (354) on the first 100 um (``--quick``, 2 cores), staggered in 0.93 of the wall time
(65.6 against 70.7 s; the heat solve of P1 T alone is cheaper than the (u, T) block system's)."""


def _case(coupling: str, quick: bool, workdir: Path, properties_T: float | None = None, scene=None,
          scene_path: Path = WORKFLOWS / "cutting-aisi1045.toml", name: str | None = None) -> dict:
    import csv

    from ..cutting.fe_run import run_cut
    from ..errors import StepCutError
    from ..freefem import FreeFemError, NewtonFailure

    if scene is None:
        scene = _scene(2, 1, quick)
        scene.cutting.volumetric = volumetric(scene.cutting.volumetric)
    scene.thermal.coupling = coupling
    scene.cutting.fe_properties_T = properties_T
    name = name or (coupling if properties_T is None else f"{coupling}-{properties_T - 273.15:.0f}C")
    out = workdir / name
    wanted = [c for c in os.environ.get("WENDEL_BENCH_CASES", "").split(",") if c]
    if not _finished(out, scene):
        if wanted and name not in wanted:
            return {"case": name, "stopped": "not run (WENDEL_BENCH_CASES)"}
        shutil.rmtree(out, ignore_errors=True)
        stopped, t0 = "", time.perf_counter()
        try:
            run_cut(scene, scene_path, out, smoke=False, progress=lambda *_: None, frames=True)
        except (NewtonFailure, StepCutError, FreeFemError) as exc:
            stopped = str(exc).split(";")[0]
        (out / "bench-case.json").write_text(json.dumps({"wall_s": time.perf_counter() - t0, "stopped": stopped}))
    case = json.loads((out / "bench-case.json").read_text()) if (out / "bench-case.json").is_file() else {}
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader((out / "cutting.csv").open())]
    s = json.loads((out / "summary.json").read_text())
    hist = list(csv.DictReader((out / "history.csv").open()))
    last = rows[-1]
    t = np.array([r["tool_travel_m"] for r in rows])
    win = t > t[-1] - WINDOW + 1e-12
    cyc = [c for c in json.loads((out / "cutting.json").read_text())["zone_temperatures"]["cycle_means"]
           if c["tool_travel_m"] > t[-1] - WINDOW]
    temps = {}
    for key, zone in (("max_T_primary_K", "T_primary"), ("max_T_secondary_K", "T_secondary")):
        v = np.array([r[key] for r in rows], dtype=float)
        temps[f"{zone}_cycles_C"] = float(np.mean([c[key] for c in cyc])) - 273.15 if cyc else float("nan")
        temps[f"{zone}_max_C"] = float(np.nanmax(v[win])) - 273.15 if np.isfinite(v[win]).any() else float("nan")
    ledger = {k: last[k] for k in ("heat_plastic_J", "heat_friction_chip_J", "heat_friction_tool_J", "heat_stored_J")}
    return {"case": name, "fe_properties_T_K": properties_T or float("nan"), "travel_um": last["tool_travel_m"] * 1e6, "increments": s["increments"],
            "newton_iterations": s["newton_iterations"], "remeshes": len(s["remeshes"]), **measure(rows), **temps,
            **ledger, "energy_balance_error": float(hist[-1].get("energy_balance_error") or "nan"),
            "wall_s": case.get("wall_s", float("nan")), "stopped": case.get("stopped", "")}


PROPERTIES_T = 773.15
"""K (500 C): the full bench cuts twice more with k and c taken there (``cutting.fe_properties_T``; 38.6 W/m/K and
672 J/kg/K for AISI 1045, against 52.6 and 420 at 0 C as the scene writes them), between Oxley's shear-plane and
interface temperatures: the FE's k and c are constant."""


@register("cutting-heat")
def cutting_heat_bench(quick: bool, workdir: Path) -> list[dict]:
    """Adiabatic against conduction with frictional heat, then both with k and c at 500 C (see the module;
    about 20 minutes, quick 3)."""
    from ..cutting.scene import predict
    workdir.mkdir(parents=True, exist_ok=True)
    cases = [("adiabatic", None), (CONDUCTION, None)] + ([("monolithic", None)] if quick else
                                                          [(CONDUCTION, PROPERTIES_T), ("adiabatic", PROPERTIES_T)])
    rows = []
    for coupling, props in cases:
        rows.append(_case(coupling, quick, workdir, props))
        (workdir / "partial.json").write_text(json.dumps(rows, indent=1))
    base = rows[0]
    for r in rows[1:]:
        if "Fc_last" in r and "Fc_last" in base:
            r["dFc_vs_adiabatic"] = (r["Fc_last"] - base["Fc_last"]) / base["Fc_last"]
            r["wall_vs_adiabatic"] = r["wall_s"] / base["wall_s"]
    ox = predict(_scene(2, 1, quick))
    rows.append({"case": "Oxley (sharp tool)", "Fc_last": ox.Fc, "Ft_last": ox.Ft, "chip_last": ox.chip_thickness * 1e6,
                 "T_primary_cycles_C": ox.T_AB - 273.15, "T_secondary_cycles_C": ox.T_int - 273.15})
    return rows


@register("cutting-ti")
def cutting_ti_bench(quick: bool, workdir: Path) -> list[dict]:
    """The titanium scene (``workflows/cutting-ti6al4v.toml``, adiabatic as written) on the graded mesh at edge size
    r/2 (5 um), cut 400 um (the scene's whole cut; ``--quick`` 100 um): whether it runs, the remesh-cycle means of
    the forces and the chip thickness over the last 160 um, beside Oxley (about 10 minutes).
    ``WENDEL_BENCH_CUT_MM``: a longer cut [mm] (0.4 to 20) on a block 0.6 mm longer than the cut (folder
    ``ti-r2-<um>um``), with the steady-state detector's spreads and drifts over the last h (``cutting-steady``'s).
    ``WENDEL_BENCH_SNAP=1``: with ``cutting.snap_to_tool`` (folder ``...-snap``). ``WENDEL_BENCH_FBAR=1``: with
    ``cutting.volumetric = "fbar"`` (folder ``...-fbar``), 0 or unset: as the scene says (the P1 cell's own).
    ``WENDEL_BENCH_CONDUCTION=1``: heat conduction and frictional heat (``thermal.coupling = "staggered"``, folder
    ``...-conduction``); ``WENDEL_BENCH_MUMPS=1``: MUMPS (``...-mumps``); ``WENDEL_BENCH_UNTIL_STEADY=1``: the cut ends
    at its steady state (``cutting.stop_when_steady``, ``...-until-steady``), ``steady_at_s`` its wall time there;
    ``WENDEL_BENCH_STEADY_MEASURE=filtered``: that state judged on the running means (``cutting.steady_measure``,
    folder ``...-filtered``; ``steady_*`` then that measure's window)."""
    import os

    from ..cutting.scene import predict
    from ..scene import load
    path = WORKFLOWS / "cutting-ti6al4v.toml"
    scene = load(path)
    mm = os.environ.get("WENDEL_BENCH_CUT_MM")
    if mm is not None:
        if not 0.4 <= float(mm) <= 20.0:
            raise ValueError(f"WENDEL_BENCH_CUT_MM = {float(mm)}: a length of cut in mm from 0.4 (the scene's) to 20")
        scene.cutting.cut_length = float(mm) * 1e-3
        scene.loading.steps = round(scene.cutting.cut_length / 5e-6)
        scene.geometry.model_extra["length"] = scene.cutting.cut_length + 0.6e-3
    snap = env_flag("WENDEL_BENCH_SNAP", "cutting.snap_to_tool")
    scene.cutting.snap_to_tool = scene.cutting.snap_to_tool or snap
    scene.cutting.volumetric = volumetric(scene.cutting.volumetric)
    fbar = scene.cutting.volumetric == "fbar"
    if quick:
        scene.cutting.cut_length *= 20 / scene.loading.steps
        scene.loading.steps = 20
    scene.cutting.edge_size = scene.cutting.edge_radius / 2
    workdir.mkdir(parents=True, exist_ok=True)
    name = ("ti-r2" if mm is None or quick else f"ti-r2-{float(mm) * 1e3:.0f}um") + ("-snap" if snap else "") + ("-fbar" if fbar else "")
    conduction = env_flag("WENDEL_BENCH_CONDUCTION", 'thermal.coupling = "staggered"')
    name += "-conduction" if conduction else ""
    if env_flag("WENDEL_BENCH_MUMPS", 'numerics.direct = "mumps"'):
        scene.numerics.direct, name = "mumps", name + "-mumps"
    if env_flag("WENDEL_BENCH_UNTIL_STEADY", "cutting.stop_when_steady"):
        scene.cutting.stop_when_steady, name = True, name + "-until-steady"
    measure = os.environ.get("WENDEL_BENCH_STEADY_MEASURE", "cycles")
    if measure not in ("cycles", "filtered"):
        raise ValueError(f"WENDEL_BENCH_STEADY_MEASURE = {measure!r}: cycles (the default) or filtered")
    if measure == "filtered":
        scene.cutting.steady_measure, name = measure, name + "-filtered"
    row = _case("staggered" if conduction else "adiabatic", quick, workdir, scene=scene, scene_path=path, name=name)
    if mm is not None and not quick:
        import csv

        from ..cutting.fe_steady import reached, steady
        cut = [{k: float(v) for k, v in r.items()} for r in csv.DictReader((workdir / name / "cutting.csv").open())]
        st = steady(cut, scene.cutting.uncut_thickness)
        row["steady_from_um"] = st["cycles"]["start_m"] * 1e6 if st["cycles"] else None
        found = st[measure]
        row["steady_to_um"] = found["end_m"] * 1e6 if found else None
        row["steady_at_s"] = reached(workdir / name, cut, found)
        row["travel_um"] = cut[-1]["tool_travel_m"] * 1e6
        row.update({f"steady_{k}": v for k, v in (found or {}).get("values", {}).items()})
        row.update({f"steady_spread_{k}": v for k, v in (found or {}).get("spreads", {}).items()})
        row["filtered_from_um"] = st["filtered"]["start_m"] * 1e6 if st["filtered"] else None
        row.update({f"fspread_{k}": v for k, v in st["last_window_spreads"]["filtered"].items()})
        row.update({f"spread_{k}": v for k, v in st["last_window_spreads"]["cycles"].items()})
        row.update({f"drift_{k}": v for k, v in st["last_window_trends"]["cycles"].items()})
    ox = predict(scene)
    return [row, {"case": "Oxley (sharp tool)", "Fc_last": ox.Fc, "Ft_last": ox.Ft, "chip_last": ox.chip_thickness * 1e6,
                  "T_primary_cycles_C": ox.T_AB - 273.15, "T_secondary_cycles_C": ox.T_int - 273.15}]
