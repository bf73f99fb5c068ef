"""Benchmark ``drilling``: cost of a removal step (remesh + chips + transfer vs the FreeFEM solve) and
the energy balance of the two temperature transfers, on workflows/drilling-3d.toml at its smoke size (h)
with 3 removal steps.

Rows: one per removal step (mesh nodes, seconds of remesh, chips quadrature, transfer and FreeFEM
launch, and the share of remesh + transfer in the step), one summary row per transfer (balance error,
transfer defect), and one row estimating the 3D target of the issue (a 10 mm bore 50 mm deep in 50
steps) from the measured cost per node and per step, with the node count of that geometry's final mesh
built here by gmsh (the FreeFEM solve is not run: an estimate, labelled so).
"""

from __future__ import annotations

import csv
import json
import math
import shutil
from pathlib import Path

from . import WORKFLOWS, register

TARGET = {"diameter": 0.010, "depth": 0.050, "steps": 50, "radius": 0.025, "height": 0.070, "h": 0.006,
          "h_bore": 0.0015}
"""The issue's 3D target: D = 10 mm, L = 50 mm (L/D = 5), 50 removal steps; workpiece and sizes assumed."""


@register("drilling")
def drilling(quick: bool, workdir: Path) -> list[dict]:
    from ..loop import run_scene
    from ..meshes import drilling as geometry
    from ..scene import load

    rows, per_node = [], []
    for transfer in (("conservative",) if quick else ("conservative", "interpolate")):
        tag = f"smoke-{transfer}"
        shutil.rmtree(workdir / tag, ignore_errors=True)
        scene = load(WORKFLOWS / "drilling-3d.toml", smoke=True)
        scene.output.png = False
        scene.drilling.transfer = transfer
        scene.drilling.steps = 3          # the smoke size (h) with 3 removal steps, whatever smoke.steps says
        root = run_scene(scene, WORKFLOWS / "drilling-3d.toml", workdir / tag, progress=lambda *_: None)
        summary = json.loads((root / "summary.json").read_text())
        steps = [r for r in csv.DictReader(open(root / "tables" / "drilling-steps.csv")) if r["kind"] != "cool"]
        for r in steps:
            f = {k: float(r[k] or 0.0) for k in ("remesh_seconds", "transfer_seconds", "chips_seconds",
                                                  "launch_seconds")}
            total = sum(f.values())
            rows.append({"case": tag, "step": int(r["step"]), "nodes": int(r["mesh_nodes"]),
                         "extrapolated_nodes": int(r["nodes_outside_old_mesh"] or 0), **f, "step_seconds": total,
                         "remesh_transfer_share": (total - f["launch_seconds"]) / total})
            per_node.append((f["launch_seconds"] / int(r["mesh_nodes"]), (total - f["launch_seconds"]) / int(r["mesh_nodes"])))
        e = summary["drilling"]["energy"]
        rows.append({"case": tag, "step": "all", "balance_error": e["balance_error"],
                     "transfer_defect_J": e["transfer_defect"], "heat_in_J": e["heat_in"],
                     "chips_J": e["chips_heat"], "wall_time": summary["wall_time"]})
    rows += removed_volume_rows(workdir)
    # the 3D target: its final mesh (gmsh only), cost from the measured seconds per node
    built = geometry.drilled(workdir / "target.msh", "cylinder", depth=TARGET["depth"], diameter=TARGET["diameter"],
                             radius=TARGET["radius"], height=TARGET["height"], h=TARGET["h"], h_bore=TARGET["h_bore"])
    first = geometry.drilled(workdir / "target-0.msh", "cylinder", depth=TARGET["depth"] / TARGET["steps"],
                             diameter=TARGET["diameter"], radius=TARGET["radius"], height=TARGET["height"],
                             h=TARGET["h"], h_bore=TARGET["h_bore"])
    solve = sum(p[0] for p in per_node) / len(per_node)
    other = sum(p[1] for p in per_node) / len(per_node)
    mean_nodes = 0.5 * (first.nodes + built.nodes)
    rows.append({"case": "estimate-3d-10x50mm-50-steps", "nodes_first": first.nodes, "nodes_last": built.nodes,
                 "solve_seconds_per_node": solve, "remesh_transfer_seconds_per_node": other,
                 "estimated_seconds": TARGET["steps"] * mean_nodes * (solve + other)})
    return rows


def removed_volume_rows(workdir: Path) -> list[dict]:
    """The removed volume of the boolean against V(d): block workpiece (flat outer faces), 3D and (r, z)."""
    from ..meshes import drilling as geometry
    from ..remesh import step as remeshing
    from ..results import vtu as output

    workdir.mkdir(parents=True, exist_ok=True)
    rows = []
    for depth in (0.001, 0.004, 0.012):
        b = geometry.drilled(workdir / "vol.msh", "block", depth=depth, diameter=0.006, x=(-0.012, 0.012),
                             y=(-0.012, 0.012), height=0.02, h=0.003, h_bore=0.0008)
        pts, cells = output.read_mesh(b.path, 3)
        removed = 0.024 * 0.024 * 0.02 - remeshing.cell_volumes(pts, cells).sum()
        s = geometry.drilled_section(workdir / "vol2.msh", depth=depth, diameter=0.006, radius=0.012, height=0.02,
                                     h=0.002, h_bore=0.0005)
        p2, c2 = output.read_mesh(s.path, 2)
        p2 = p2[:, :2]
        removed2 = math.pi * 0.012 ** 2 * 0.02 - (2 * math.pi * p2[c2].mean(axis=1)[:, 0]
                                                  * remeshing.cell_volumes(p2, c2)).sum()
        exact = geometry.bore_volume(depth, 0.003, 118.0)
        rows.append({"case": "removed-volume", "step": f"depth {depth * 1e3:g} mm", "volume_exact": exact,
                     "volume_3d_rel_error": removed / exact - 1, "volume_rz_rel_error": removed2 / exact - 1})
    return rows
