"""Benchmark of interior penalty DG against continuous Lagrange elements (``wendel bench dg``).

Three parts, each one row per run (same machine, same launch path, interleaved):

* ``cook``: Cook's membrane at nu = 0.499975 (workflows/cook-dg.toml): tip displacement u_y(48, 52) against
  Krysl's converged 16.4326 for CG P1, CG P2, DG P1, DG P2 at several mesh sizes, with DoFs and wall time;
* ``mms``: the manufactured solution of workflows/smoke-mms.toml (nu = 0.25, no locking) for the same four
  methods; then the cost ratio DG/CG at equal broken-H1 error (``ratio`` rows: the wall time and the work
  time, assembly + solve, each interpolated log-log at the error of the finest common level);
* ``step8``: deal.II step-8's problem (workflows/smoke.toml) with CG P1 and DG P1 on one mesh; both fields and
  their difference in ``step8-cg-dg.vtu`` beside the results, the strain energy of each against CG P2 on h/2.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..scene import load
from ..scene.blocks.discretization import Discretization
from . import WORKFLOWS, register, run_fresh

COOK_REFERENCE = 16.432584376299037
"""u_y at (48, 52) of Cook's membrane with lambda = 7500, G = 0.375, total shear 1 (P. Krysl, FinEALE
benchmark Cook_3D_strain: NICE-T6 results extrapolated by Richardson)."""

METHODS = {"cg1": ("cg", 1), "cg2": ("cg", 2), "dg1": ("dg", 1), "dg2": ("dg", 2)}


def _run(path: Path, method: str, h: float, out: Path, solver: str = "direct") -> dict:
    """One run of the scene at size ``h`` with ``method``; its summary and last record."""
    kind, order = METHODS[method]
    scene = load(path)
    scene.geometry.h = h
    scene.numerics.solver = solver
    block = getattr(scene, "discretization", None)
    if kind == "dg":
        scene.discretization = Discretization(kind="dg", order=order, gamma_mu=block.gamma_mu if block else 20.0,
                                              gamma_lambda=block.gamma_lambda if block else 20.0)
    else:
        scene.discretization = None
        scene.elasticity.order = order
    scene.output.png = False
    s = run_fresh(scene, path, out)
    rec = json.loads(sorted((out / "fem").glob("inc-*/record.json"))[-1].read_text())
    ph = s["wall_time_by_phase"]
    return {"dofs": rec["dofs"], "wall_time": s["wall_time"], "work_time": ph["assembly"] + ph["linear_solve"],
            "record": rec}


def _cook(quick: bool, workdir: Path) -> list[dict]:
    sizes = [4.0, 2.0] if quick else [4.0, 2.0, 1.0, 0.5]
    rows = []
    for h in sizes:
        for method in METHODS:
            if method == "dg2" and h < 1.0:
                continue                        # 165k DoFs: already within 0.1 % at h = 2
            r = _run(WORKFLOWS / "cook-dg.toml", method, h, workdir / f"cook-{method}-h{h:g}")
            tip = r["record"]["probe_uy"]
            rows.append({"case": "cook", "method": method, "h": h, "dofs": r["dofs"], "tip_uy": tip,
                         "error": tip / COOK_REFERENCE - 1.0, "wall_time": r["wall_time"], "work_time": r["work_time"]})
    return rows


def _at_error(points: list[tuple[float, float]], error: float) -> float:
    """Time at ``error``, log-log interpolated between the two (error, time) pairs around it (or the last two).

    >>> round(_at_error([(0.1, 1.0), (0.01, 100.0)], 0.03162), 2)
    10.0
    """
    pts = sorted(points)
    i = next((k for k in range(len(pts) - 1) if pts[k][0] <= error <= pts[k + 1][0]), 0)
    (e0, t0), (e1, t1) = pts[i], pts[i + 1]
    return t0 * math.exp(math.log(t1 / t0) / math.log(e1 / e0) * math.log(error / e0))


def _mms(quick: bool, workdir: Path) -> list[dict]:
    sizes = {"cg1": [0.1, 0.05, 0.025, 0.0125], "dg1": [0.1, 0.05, 0.025], "cg2": [0.2, 0.1, 0.05],
             "dg2": [0.2, 0.1, 0.05]}
    if quick:
        sizes = {m: s[:2] for m, s in sizes.items()}
    rows, runs = [], {}
    for method, hs in sizes.items():
        for h in hs:
            r = _run(WORKFLOWS / "smoke-mms.toml", method, h, workdir / f"mms-{method}-h{h:g}")
            rec = r["record"]
            err = rec["error_h1"] / rec["reference_h1"]
            runs.setdefault(method, []).append((err, r["wall_time"], r["work_time"]))
            rows.append({"case": "mms", "method": method, "h": h, "dofs": r["dofs"], "error": err,
                         "wall_time": r["wall_time"], "work_time": r["work_time"]})
    for k in ("1", "2"):
        cg, dg = runs["cg" + k], runs["dg" + k]
        target = max(min(e for e, _, _ in cg), min(e for e, _, _ in dg))   # reached by both
        wall = _at_error([(e, t) for e, t, _ in dg], target) / _at_error([(e, t) for e, t, _ in cg], target)
        work = _at_error([(e, w) for e, _, w in dg], target) / _at_error([(e, w) for e, _, w in cg], target)
        rows.append({"case": "ratio", "method": f"dg{k}/cg{k}", "error": target, "wall_time": wall, "work_time": work})
    return rows


def _step8(quick: bool, workdir: Path) -> list[dict]:
    from ..results.vtu import read_array, read_mesh, write_vtu

    h = 0.1 if quick else 0.05
    path = WORKFLOWS / "smoke.toml"
    fine = _run(path, "cg2", h / 2, workdir / "step8-fine")["record"]["strain_energy"]
    rows, fields = [], {}
    for method in ("cg1", "dg1"):
        out = workdir / f"step8-{method}"
        r = _run(path, method, h, out)
        fields[method] = read_array(out / "fem" / "inc-0001" / "u.node.txt").reshape(-1, 2)
        energy = r["record"]["strain_energy"]
        rows.append({"case": "step8", "method": method, "h": h, "dofs": r["dofs"], "energy": energy,
                     "error": abs(energy / fine - 1.0), "wall_time": r["wall_time"], "work_time": r["work_time"]})
    points, cells = read_mesh(workdir / "step8-cg1" / "mesh.msh", 2)
    pad = lambda u: np.column_stack([u, np.zeros(len(u))])
    diff = fields["dg1"] - fields["cg1"]
    write_vtu(workdir / "step8-cg-dg.vtu", points, cells, 2,
              {"u_cg": pad(fields["cg1"]), "u_dg": pad(fields["dg1"]), "u_dg_minus_cg": pad(diff)}, {})
    scale = np.abs(fields["cg1"]).max()
    for row in rows:
        row["max_difference"] = float(np.abs(diff).max() / scale)     # relative to max |u_cg|
    return rows


@register("dg")
def dg_bench(quick: bool, workdir: Path) -> list[dict]:
    """Cook's membrane (locking), the manufactured solution (cost at equal error) and step-8, CG against DG."""
    workdir.mkdir(parents=True, exist_ok=True)
    return _cook(quick, workdir) + _mms(quick, workdir) + _step8(quick, workdir)
