"""Benchmarks of the quasi-static loop: remeshing cost against solve cost, and the upsetting scene with
and without remeshing (``wendel bench remesh``)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from .. import loop as runmod
from ..scene import load
from . import WORKFLOWS, register


@register("remesh")
def remesh_bench(quick: bool, workdir: Path) -> list[dict]:
    """Upsetting with and without remeshing: quality, completion, remesh+transfer vs solve time."""
    path = WORKFLOWS / "upsetting.toml"
    rows = []
    for variant in ("with remeshing", "without remeshing"):
        scene = load(path, smoke=quick)
        scene.output.png = False
        if variant == "without remeshing":
            scene.remesh = None
        out = workdir / variant.replace(" ", "-")
        shutil.rmtree(out, ignore_errors=True)
        error = ""
        try:
            runmod.run_scene(scene, path, out, smoke=quick, progress=lambda *_: None)
        except Exception as exc:       # noqa: BLE001 - the failure is the measurement
            error = str(exc).splitlines()[0][:120]
        s = json.loads((out / "summary.json").read_text())
        hist = (out / "history.csv").read_text().splitlines()
        head = hist[0].split(",")
        q = [float(r.split(",")[head.index("min_quality")]) for r in hist[1:]]
        inv = [int(float(r.split(",")[head.index("inverted")])) for r in hist[1:]]
        ph = s["wall_time_by_phase"]
        solve_per_inc = (ph["assembly"] + ph["linear_solve"] + ph["constitutive"]) / max(s["increments"], 1)
        rem = s.get("remeshes", [])
        rm_t = [r["remesh_seconds"] + r["transfer_seconds"] for r in rem]
        rows.append({
            "variant": variant, "completed": s["completed"], "increments": s["increments"],
            "final_load_factor": s["last_increment"].get("load_factor"), "remeshes": len(rem),
            "final_min_quality": q[-1] if q else None, "worst_min_quality": min(q) if q else None,
            "inverted_elements_at_end": inv[-1] if inv else None, "newton_iterations": s["newton_iterations"],
            "dofs_at_end": s["dofs"], "wall_time": s["wall_time"],
            "mean_solve_per_increment": solve_per_inc,
            "mean_remesh_transfer": sum(rm_t) / len(rm_t) if rm_t else None,
            "remesh_transfer_share": (sum(rm_t) / len(rm_t)) / solve_per_inc if rm_t else None,
            "integral_p_change": max((abs(r["integral_p_after"] / r["integral_p_before"] - 1) for r in rem
                                      if r.get("integral_p_before")), default=None),
            "error": error,
        })
    return rows
