"""Benchmark ``axisymmetric``: the sphere indentation of ``hertz-3d`` (3D, P1 tetrahedra, CG) against the same
physics in (r, z) (``axisym-hertz``, direct solver) at equal contact-radius error.

The 3D scene runs at its own mesh; the axisymmetric one at contact-zone sizes from coarse to fine. The row
``axisymmetric at equal error`` is the cheapest (r, z) run whose contact-radius error is at most the 3D
one; ``dofs_ratio`` and ``time_ratio`` are 3D over (r, z), taken within this run. The bodies differ a little
(a 2 m x 2 m x 1 m block against a cylinder of radius 1 m and height 1 m, both clamped at the bottom);
Hertz's reference uses each run's own force.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from . import WORKFLOWS, register


def _run(scene_file: str, workdir: Path, contact_h: float | None = None) -> dict:
    from ..loop import run_scene
    from ..scene import load

    scene = load(WORKFLOWS / scene_file)
    scene.output.png = False
    scene.output.vtu = False
    if contact_h is not None:
        scene.geometry.model_extra["refine"] = dict(scene.geometry.model_extra["refine"], h=contact_h)
    shutil.rmtree(workdir, ignore_errors=True)
    root = run_scene(scene, WORKFLOWS / scene_file, workdir, progress=lambda *_: None)
    s = json.loads((root / "summary.json").read_text())
    rec = json.loads((sorted((root / "fem").glob("inc-*"))[-1] / "record.json").read_text())
    return {"dofs": s["dofs"], "wall_time": s["wall_time"], "newton_iterations": s["newton_iterations"],
            "error_contact_size": rec["error_contact_size"], "error_max_pressure": rec["error_max_pressure"],
            "contact_force": rec["contact_force"]}


@register("axisymmetric")
def axisymmetric(quick: bool, workdir: Path) -> list[dict]:
    """hertz-3d against axisym-hertz at contact-zone sizes 10, 5 and 2.5 mm (quick: 10 and 5 mm)."""
    rows = [{"case": "3D hertz-3d", "contact_h": 0.01, **_run("hertz-3d.toml", workdir / "3d")}]
    ref = rows[0]
    sizes = [0.01, 0.005] if quick else [0.01, 0.005, 0.0025]
    axi = []
    for hc in sizes:
        axi.append({"case": "axisymmetric", "contact_h": hc, **_run("axisym-hertz.toml", workdir / f"axi-{hc:g}", hc)})
    rows += axi
    equal = [r for r in axi if r["error_contact_size"] <= ref["error_contact_size"]]
    if equal:
        best = min(equal, key=lambda r: r["wall_time"])
        rows.append({**best, "case": "axisymmetric at equal error", "dofs_ratio": ref["dofs"] / best["dofs"],
                     "time_ratio": ref["wall_time"] / best["wall_time"]})
    return rows
