"""``wendel bench cutting`` and ``cutting-isothermal``: the FE cut of the AISI 1045 scene, adiabatic (as the
scene says) and isothermal (the same scene with its heating off).

Each case runs ``workflows/cutting-aisi1045.toml`` (``--quick``: its first 20 increments) through
:func:`wendel.cutting.fe_run.run_cut`; a run that stops (Newton failure after the step cuts) is reported as
far as it got, with the reason. Per case: increments and tool travel reached, F_c and F_t at the end and
their mean over the last 20 um of travel, the chip rise, contact length and chip thickness, the largest
plastic strain (and temperature), the wall time and the share of remeshing + transfer, beside the Oxley
prediction of the same scene. ``WENDEL_BENCH_FBAR``: 1 or 0 sets ``cutting.volumetric`` (``"fbar"``, ``"cell"``)
instead of the scene's.
"""

from __future__ import annotations

import json
import shutil
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


@register("cutting")
def cutting_bench(quick: bool, workdir: Path) -> list[dict]:
    """The scene as written (adiabatic); ``cutting-isothermal`` is the same cut without heating (each ~15 min)."""
    return [_case("adiabatic", WORKFLOWS / "cutting-aisi1045.toml", workdir, 20 if quick else None)]


@register("cutting-isothermal")
def cutting_isothermal_bench(quick: bool, workdir: Path) -> list[dict]:
    return [_case("isothermal", WORKFLOWS / "cutting-aisi1045.toml", workdir, 20 if quick else None)]
