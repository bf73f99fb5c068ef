"""``wendel bench cutting``: the steel and the titanium cut to their steady state, as their scenes say
(``workflows/cutting-aisi1045-steady.toml``, ``workflows/cutting-ti6al4v-steady.toml``: F-bar, conduction and
frictional heat, edge r/2, MUMPS, ``cutting.stop_when_steady``), one after the other (about 36 and 16 minutes
on one core; ``--quick``: each scene's first 20 increments, no steady state; ``WENDEL_BENCH_CASES``,
``WENDEL_BENCH_RAKE``, ``WENDEL_BENCH_SPEED``, ``WENDEL_BENCH_FRICTION``: one of them, another rake, speed or
Coulomb coefficient on the rake face). Per cut: where it ended and why,
the steady window (its start and end, F_c, F_t and chip thickness with their spreads), the run's wall time
(``summary.json``: up to the stop, Python's start and the report excepted) and the bench's (with the report and
its frames), the shares of the run's wall time in remeshing + transfer and in failed tries (increments whose
step was cut, launches that kept none), Newton iterations (and how many of its steps changed the contact or
friction sets: :func:`wendel.cutting.fe_newton.newton_sets`) and remeshes, beside the Oxley prediction of the same
scene and the differences.

``cutting-adiabatic`` and ``cutting-isothermal``: the prototype steel scene ``workflows/cutting-aisi1045.toml``
as written (P1 cells, adiabatic, 0.6 mm) and without its heating. Each case runs through
:func:`wendel.cutting.fe_run.run_cut`; a run that stops (Newton failure after the step cuts) is reported as
far as it got, with the reason. ``WENDEL_BENCH_FBAR``: 1 or 0 sets ``cutting.volumetric`` (``"fbar"``,
``"cell"``) instead of the scene's (``cutting-adiabatic``, ``cutting-isothermal``).
"""

from __future__ import annotations

import json
import shutil
import sys
import time
from pathlib import Path

from . import WORKFLOWS, register, volumetric


def _case(name: str, scene_path: Path, workdir: Path, steps: int | None) -> dict:
    from ..cutting.fe_run import run_cut
    from ..cutting.scene import predict
    from ..errors import StepCutError
    from ..freefem import FreeFemError, NewtonFailure
    from ..scene import load

    scene = load(scene_path)
    scene.cutting.volumetric = volumetric(scene.cutting.volumetric)
    if name == "isothermal":
        scene.thermal.beta = 0.0      # adiabatic without Taylor-Quinney heat: the cut stays at T_room
    if steps:
        scene.cutting.cut_length *= steps / scene.loading.steps
        scene.loading.steps = steps
    out = workdir / name
    if out.is_dir():
        shutil.rmtree(out)          # the bench's own folder of an earlier run
    t0 = time.perf_counter()
    stopped = ""
    try:
        run_cut(scene, scene_path, out, smoke=False, progress=lambda *_: None, frames=True)
    except (NewtonFailure, StepCutError, FreeFemError) as exc:
        stopped = str(exc).split(";")[0]
    wall = time.perf_counter() - t0
    rows = [json.loads(json.dumps(r)) for r in _rows(out)]
    s = json.loads((out / "summary.json").read_text())
    remesh = sum(r.get("remesh_seconds", 0) + r.get("transfer_seconds", 0) for r in s["remeshes"])
    last = rows[-1]
    travel = last["tool_travel_m"]
    tail = [r for r in rows if r["tool_travel_m"] >= travel - 20e-6]
    ox = predict(scene)
    return {"case": name, "increments": s["increments"], "travel_um": travel * 1e6,
            "cut_length_um": scene.cutting.cut_length * 1e6, "Fc_N": last["Fc_N"], "Ft_N": last["Ft_N"],
            "Fc_last20um_N": sum(r["Fc_N"] for r in tail) / len(tail),
            "Ft_last20um_N": sum(r["Ft_N"] for r in tail) / len(tail),
            "chip_rise_um": last["chip_rise_m"] * 1e6, "contact_length_um": last["contact_length_m"] * 1e6,
            "chip_thickness_um": last["chip_thickness_m"] * 1e6, "max_plastic_strain": last["max_plastic_strain"],
            "max_temperature_K": last["max_temperature_K"], "elements": last["elements"],
            "remeshes": len(s["remeshes"]), "newton_iterations": s["newton_iterations"], "wall_s": wall,
            "remesh_share": remesh / wall, "oxley_Fc_N": ox.Fc, "oxley_Ft_N": ox.Ft,
            "oxley_chip_um": ox.chip_thickness * 1e6, "stopped": stopped}


def _rows(out: Path) -> list[dict]:
    import csv
    return [{k: float(v) for k, v in r.items()} for r in csv.DictReader((out / "cutting.csv").open())]


STEADY = (("steel", "cutting-aisi1045-steady.toml"), ("titanium", "cutting-ti6al4v-steady.toml"))


def _to_steady(name: str, scene_path: Path, workdir: Path, quick: bool) -> dict:
    from ..cutting.fe_run import run_cut
    from ..errors import StepCutError
    from ..freefem import FreeFemError, NewtonFailure
    from ..scene import load

    scene = load(scene_path)
    if quick:
        scene.cutting.cut_length *= 20 / scene.loading.steps
        scene.loading.steps = 20
    folder = name
    rake, speed = _number("WENDEL_BENCH_RAKE", -20.0, 30.0), _number("WENDEL_BENCH_SPEED", 20.0, 1000.0)
    if rake is not None:
        scene.cutting.rake, folder = rake, f"{folder}-rake{rake:g}"
    if speed is not None:
        scene.cutting.speed, folder = speed / 60.0, f"{folder}-V{speed:g}"
    mu = _number("WENDEL_BENCH_FRICTION", 0.0, 2.0)
    if mu is not None:
        scene.cutting.friction, folder = mu, f"{folder}-mu{mu:g}"
    out = workdir / folder
    shutil.rmtree(out, ignore_errors=True)          # the bench's own folder of an earlier run
    t0, stopped = time.perf_counter(), ""
    try:
        run_cut(scene, scene_path, out, smoke=False, progress=lambda *_: None, frames=True)
    except (NewtonFailure, StepCutError, FreeFemError) as exc:
        stopped = str(exc).split(";")[0]
    return row(folder, name, scene, scene_path, out, time.perf_counter() - t0, stopped)


def row(case: str, material: str, scene, scene_path: Path, out: Path, bench_wall: float, stopped: str) -> dict:
    """The bench's row of the cut ``scene`` of ``material`` (``steel``, ``titanium``: the measured cuts it is
    compared with, :data:`wendel.cutting.experiments.MEASURED`) in the run folder ``out`` (see the module);
    ``first_<measure>_*``: the first window of each steady measure (:func:`wendel.cutting.fe_steady.steady`)
    whether or not the run stopped there, ``last_cycles_spread_*``: the remesh-cycle means' spreads over the last
    window."""
    from ..cutting.experiments import reference
    from ..cutting.fe_newton import newton_sets
    from ..cutting.fe_steady import steady, window
    from ..cutting.scene import predict
    rows, s = _rows(out), json.loads((out / "summary.json").read_text())
    wall, ph = s["wall_time"], s["wall_time_by_phase"]
    stop = json.loads((out / "steady-stop.json").read_text()) if (out / "steady-stop.json").is_file() else None
    win = stop["window"] if stop else {}
    v, sp = win.get("values", {}), win.get("spreads", {})
    ox = predict(scene)
    nan = float("nan")
    fc, ft, chip = v.get("Fc_N", nan), v.get("Ft_N", nan), v.get("chip_thickness_m", nan) * 1e6
    c = scene.cutting
    st = steady(rows, c.uncut_thickness)
    first = {}
    for m in ("cycles", "filtered"):
        w = st[m] or {}
        first.update({f"first_{m}_from_um": w.get("start_m", nan) * 1e6, f"first_{m}_to_um": w.get("end_m", nan) * 1e6,
                      **{f"first_{m}_{k}": w.get("values", {}).get(k, nan) for k in ("Fc_N", "Ft_N")},
                      f"first_{m}_chip_um": w.get("values", {}).get("chip_thickness_m", nan) * 1e6,
                      **{f"first_{m}_spread_{k}": w.get("spreads", {}).get(k, nan)
                         for k in ("Fc_N", "Ft_N", "chip_thickness_m")}})
    first.update({f"last_cycles_spread_{k}": v for k, v in st["last_window_spreads"]["cycles"].items()})
    last = window(rows, c.uncut_thickness)      # the last h's travel-weighted means, steady or not
    first.update({"last_h_Fc_N": last["steady_Fc_N"], "last_h_Ft_N": last["steady_Ft_N"],
                  "last_h_chip_um": last["steady_chip_m"] * 1e6})
    exp = reference(material, c.speed * 60, c.uncut_thickness * 1e3, c.rake) or {}
    same_width = exp.get("width_mm") is not None and abs(exp["width_mm"] - c.width * 1e3) < 1e-9
    efc, eft = (exp["Fc_N"], exp["Ft_N"]) if same_width else (nan, nan)     # totals only at the scene's width
    return {"case": case, "scene": scene_path.name, "rake_deg": c.rake, "V_m_per_min": c.speed * 60, "mu": c.friction,
            "steady": stop is not None,
            "measure": scene.cutting.steady_measure, "ended_um": rows[-1]["tool_travel_m"] * 1e6,
            "increments": s["increments"], "steady_from_um": win.get("start_m", nan) * 1e6,
            "steady_to_um": win.get("end_m", nan) * 1e6, "Fc_N": fc, "Ft_N": ft, "chip_um": chip,
            "h_ratio": chip / (scene.cutting.uncut_thickness * 1e6),
            **{f"spread_{k}": sp.get(k, nan) for k in ("Fc_N", "Ft_N", "chip_thickness_m")},
            "wall_s": wall, "bench_wall_s": bench_wall, "remesh_share": ph.get("remesh", 0.0) / wall,
            "failed_share": (ph.get("failed_increments", 0.0) + ph.get("failed_launches", 0.0)) / wall,
            "newton_iterations": s["newton_iterations"], "remeshes": len(s["remeshes"]), "step_cuts": s["step_cuts"],
            **{k: v for k, v in newton_sets(out).items() if k not in ("increments", "iterations")},
            "oxley_Fc_N": ox.Fc, "oxley_Ft_N": ox.Ft, "oxley_chip_um": ox.chip_thickness * 1e6,
            "dFc_oxley": fc / ox.Fc - 1, "dFt_oxley": ft / ox.Ft - 1,
            "dchip_oxley": chip / (ox.chip_thickness * 1e6) - 1,
            "Ft_over_Fc": ft / fc, "oxley_Ft_over_Fc": ox.Ft / ox.Fc,
            "exp_Fc_N": efc, "exp_Ft_N": eft, "dFc_exp": fc / efc - 1, "dFt_exp": ft / eft - 1,
            "exp_Ft_over_Fc": exp.get("Ft_over_Fc", nan), "exp_h_ratio": exp.get("h_ratio") or nan,
            "experiment": exp.get("source", "none at these conditions"), **first, "stopped": stopped}


def _number(var: str, lo: float, hi: float) -> float | None:
    """A number from the environment variable ``var`` in [lo, hi], None if unset; anything else refused by name."""
    import math
    import os
    v = os.environ.get(var)
    if v is None:
        return None
    try:
        x = float(v)
    except ValueError:
        x = math.nan
    if not lo <= x <= hi:
        raise ValueError(f"{var} = {v!r}: a number from {lo:g} to {hi:g}")
    return x


@register("cutting")
def cutting_bench(quick: bool, workdir: Path) -> list[dict]:
    """The steel and the titanium scene cut to their steady state (see the module; about 55 minutes alone, quick 6).
    ``WENDEL_BENCH_CASES``: the cuts to make (``steel``, ``titanium``, comma-separated; both if unset);
    ``WENDEL_BENCH_RAKE`` [deg], ``WENDEL_BENCH_SPEED`` [m/min], ``WENDEL_BENCH_FRICTION`` [1]: that rake, cutting
    speed or Coulomb coefficient instead of the scene's (folders ``<case>-rake<deg>``, ``<case>-V<speed>``,
    ``<case>-mu<mu>``; the measured cut at that rake and speed, if any, beside it)."""
    import os
    wanted = [c for c in os.environ.get("WENDEL_BENCH_CASES", "").split(",") if c]
    unknown = sorted(set(wanted) - {name for name, _ in STEADY})
    if unknown:
        raise ValueError(f"WENDEL_BENCH_CASES = {','.join(wanted)!r}: {', '.join(unknown)} unknown; "
                         "valid: steel, titanium")
    return [_to_steady(name, WORKFLOWS / path, workdir, quick) for name, path in STEADY if not wanted or name in wanted]


@register("cutting-adiabatic")
def cutting_adiabatic_bench(quick: bool, workdir: Path) -> list[dict]:
    """The prototype scene as written (adiabatic); ``cutting-isothermal`` is the same cut without heating
    (each ~15 min)."""
    return [_case("adiabatic", WORKFLOWS / "cutting-aisi1045.toml", workdir, 20 if quick else None)]


@register("cutting-isothermal")
def cutting_isothermal_bench(quick: bool, workdir: Path) -> list[dict]:
    return [_case("isothermal", WORKFLOWS / "cutting-aisi1045.toml", workdir, 20 if quick else None)]


def main(argv: list[str]) -> int:
    """``python -m wendel.bench.cutting RUN MATERIAL``: the bench's row of a cut's run folder (a bench's work folder
    or a ``wendel run`` of a cutting scene), as the scene was run, against the measured cuts of ``MATERIAL``
    (``steel``, ``titanium``); one ``key value`` a line."""
    from ..cutting.experiments import MEASURED
    from ..cutting.fe_run import cutting_scene
    if len(argv) != 2 or argv[1] not in MEASURED:
        print(f"usage: python -m wendel.bench.cutting RUN {'|'.join(MEASURED)}", file=sys.stderr)
        return 2
    out = Path(argv[0])
    scene = cutting_scene(out)
    if scene is None:
        print(f"{out}: not the run folder of a cutting scene", file=sys.stderr)
        return 2
    for k, v in row(out.name, argv[1], scene, out / "scene.toml", out, float("nan"), "").items():
        print(k, f"{v:.6g}" if isinstance(v, float) else v)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
