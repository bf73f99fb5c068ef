"""Benchmark ``drilling``: the issue's deep bore, a 10 mm bore 50 mm deep (L/D = 5) in 50 removal steps.

Rows (``results/bench/drilling.csv``):

- ``rz-deep``: workflows/drilling-deep-rz.toml run whole in the axisymmetric (r, z) model: one row per
  removal step (mesh nodes, seconds of remesh (gmsh), transfer, chips quadrature and the FreeFEM launch,
  and the share of remesh + transfer + chips in the step), and a summary row (wall time, energy balance);
- ``3d-deep-first-K`` and ``3d-deep-last-K``: the same bore in 3D (:func:`deep_3d_text`: the (r, z) scene on
  the drilled-cylinder builder, h = 6 mm, h_bore = 1.5 mm; not a workflow: its smoke run alone takes 50 s),
  its first ``K`` removal steps and its last ``K`` (from a bore pre-drilled to 47 mm: ``start_depth``), the
  same 1 mm steps and step times, one row per step; then ``3d-deep-extrapolated``: the whole 50-step run
  estimated as 50 x the mean of the step times measured at the two ends (the node count grows about
  linearly with the depth; an extrapolation, labelled so: the 44 steps between are not run);
- ``rz-transfer-*``: workflows/drilling-rz.toml at its smoke size with the conservative transfer and with
  nodal interpolation (energy balance error and the heat the transfer created);
- ``removed-volume``: the removed volume of the boolean against the analytic bore volume, 3D and (r, z).

``--quick`` leaves out the 3D steps. ``drilling-3d`` (opt-in) runs the 3D deep bore whole, all 50 steps.
"""

from __future__ import annotations

import csv
import json
import math
import time
from pathlib import Path

from . import WORKFLOWS, register, run_fresh

K_3D = 3
"""Removal steps of the 3D deep bore that are run (of 50)."""


def _run(scene, path: Path, out: Path) -> tuple[Path, dict, float]:
    t0 = time.perf_counter()
    summary = run_fresh(scene, path, out)
    return out, summary, time.perf_counter() - t0


def _step_rows(case: str, root: Path) -> list[dict]:
    rows = []
    for r in csv.DictReader(open(root / "tables" / "drilling-steps.csv")):
        if r["kind"] == "cool":
            continue
        f = {k: float(r.get(k) or 0.0) for k in ("remesh_seconds", "transfer_seconds", "chips_seconds", "launch_seconds")}
        total = sum(f.values())
        rows.append({"case": case, "step": int(r["step"]), "depth_mm": float(r["depth"]) * 1e3,
                     "nodes": int(r["mesh_nodes"]), "extrapolated_nodes": int(r["nodes_outside_old_mesh"] or 0),
                     **f, "step_seconds": total, "remesh_transfer_share": (total - f["launch_seconds"]) / total})
    return rows


def _summary_row(case: str, summary: dict, wall: float, steps: list[dict]) -> dict:
    e = summary["drilling"]["energy"]
    n = len(steps)
    return {"case": case, "step": "all", "removal_steps": n, "wall_seconds": wall,
            "remesh_transfer_seconds": sum(s["step_seconds"] - s["launch_seconds"] for s in steps),
            "launch_seconds": sum(s["launch_seconds"] for s in steps),
            "mean_remesh_transfer_share": sum(s["remesh_transfer_share"] for s in steps) / max(n, 1),
            "balance_error": e["balance_error"], "transfer_defect_J": e["transfer_defect"], "heat_in_J": e["heat_in"],
            "chips_J": e["chips_heat"], "nodes_last": steps[-1]["nodes"] if steps else 0,
            "probes_peak_K": json.dumps({k: round(v, 2) for k, v in summary["drilling"]["probes_peak"].items()})}


@register("drilling")
def drilling(quick: bool, workdir: Path) -> list[dict]:
    from ..scene import load

    workdir.mkdir(parents=True, exist_ok=True)
    rows = []
    # the (r, z) deep bore, whole
    path = WORKFLOWS / "drilling-deep-rz.toml"
    scene = load(path)
    scene.output.png = False
    root, summary, wall = _run(scene, path, workdir / "rz-deep")
    steps = _step_rows("rz-deep", root)
    rows += steps + [_summary_row("rz-deep", summary, wall, steps)]
    # the 3D deep bore: its first K steps, then the extrapolation to 50
    if not quick:
        path = workdir / "drilling-deep-3d.toml"
        path.write_text(deep_3d_text())
        ends = {}
        for end in ("first", "last"):      # steps 1..K of the schedule, and its last K (from a pre-drilled bore)
            scene = load(path)
            scene.output.png = False
            b = scene.drilling
            n_steps, dd, depth = b.steps, (b.depth - b.start_depth) / b.steps, b.depth
            b.cooling = 0.0
            if end == "first":
                b.depth, b.steps = b.start_depth + K_3D * dd, K_3D
            else:
                b.start_depth, b.steps = depth - K_3D * dd, K_3D
            case = f"3d-deep-{end}-{K_3D}"
            root, summary, wall = _run(scene, path, workdir / case)
            steps = _step_rows(case, root)
            rows += steps + [_summary_row(case, summary, wall, steps)]
            ends[end] = steps[1:]      # the steps with a remesh + transfer (the first builds the body only)
        # nodes grow about linearly with the depth: the mean step costs the mean of the two ends
        mean = lambda key, end: sum(s[key] for s in ends[end]) / len(ends[end])
        step_s = 0.5 * (mean("step_seconds", "first") + mean("step_seconds", "last"))
        launch_s = 0.5 * (mean("launch_seconds", "first") + mean("launch_seconds", "last"))
        rows.append({"case": "3d-deep-extrapolated", "step": f"{n_steps} (estimate)",
                     "nodes_first": ends["first"][0]["nodes"], "nodes_last": ends["last"][-1]["nodes"],
                     "step_seconds_first": mean("step_seconds", "first"), "step_seconds_last": mean("step_seconds", "last"),
                     "mean_remesh_transfer_share": 1 - launch_s / step_s, "estimated_seconds": n_steps * step_s})
    # conservative transfer against interpolation, (r, z) at smoke size
    path = WORKFLOWS / "drilling-rz.toml"
    for transfer in ("conservative", "interpolate"):
        scene = load(path, smoke=True)
        scene.output.png = False
        scene.drilling.transfer = transfer
        root, summary, wall = _run(scene, path, workdir / f"rz-{transfer}")
        steps = _step_rows(f"rz-transfer-{transfer}", root)
        rows.append(_summary_row(f"rz-transfer-{transfer}", summary, wall, steps))
    rows += removed_volume_rows(workdir)
    return rows


@register("drilling-3d")
def drilling_3d(quick: bool, workdir: Path) -> list[dict]:
    """The 3D deep bore of :func:`deep_3d_text` run whole: 50 removal steps, no extrapolation (opt-in: about
    7 minutes here). ``--quick`` runs its first 10 steps."""
    from ..scene import load

    workdir.mkdir(parents=True, exist_ok=True)
    path = workdir / "drilling-deep-3d.toml"
    path.write_text(deep_3d_text())
    scene = load(path)
    scene.output.png = False
    b = scene.drilling
    if quick:
        b.depth, b.steps = b.start_depth + 10 * (b.depth - b.start_depth) / b.steps, 10
    case = f"3d-deep-{b.steps}-steps"
    root, summary, wall = _run(scene, path, workdir / case)
    steps = _step_rows(case, root)
    return steps + [_summary_row(case, summary, wall, steps)]


def deep_3d_text() -> str:
    """workflows/drilling-deep-rz.toml made 3D: the drilled-cylinder builder, a clamped base in x, y and z, and the
    coarser sizes a 3D run on this machine affords (h = 6 mm, h_bore = 1.5 mm)."""
    text = (WORKFLOWS / "drilling-deep-rz.toml").read_text()
    for old, new in (('builder = "drilled-section"', 'builder = "drilled-cylinder"'),
                     ('plane = "axisymmetric"', 'plane = "strain"      '),
                     ("h = 0.003                # m: element size away", "h = 0.006                # m: element size away"),
                     ("uy = 0.0                 # m\n", "uy = 0.0                 # m\nuz = 0.0                 # m\n"),
                     ("h_bore = 0.0005          # m", "h_bore = 0.0015          # m")):
        if old not in text:
            raise ValueError(f"workflows/drilling-deep-rz.toml: {old!r} not found (the bench's 3D variant edits it)")
        text = text.replace(old, new, 1)
    return text


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
