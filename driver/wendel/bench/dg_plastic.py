"""Benchmark of J2 plasticity with DG P1 and P2 against CG P1 (``wendel bench dg-plastic``).

Two parts, one row per run (same machine, same launch path):

* ``cylinder``: Hill's thick-walled cylinder (workflows/cylinder-dg-p2.toml, perfect plasticity, plane strain,
  nu = 0.49, internal pressure to 74 MPa): the relative error of the plastic radius against Hill's closed form
  for CG P1, DG P1 and DG P2 at several mesh sizes, with DoFs, Newton iterations and wall time;
* ``beam``: the short 3D cantilever of workflows/beam-dg-p2-3d.toml (perfect plasticity, 15 MN on its end, past
  first yield): tip deflection u_z(4, 0.5, 0.5) of CG P1, DG P1 and DG P2, the error against CG P1 on the finest
  mesh (h = 0.0625 m; no closed form).
"""

from __future__ import annotations

import json
from pathlib import Path

from . import WORKFLOWS, register
from .dg import _run

CYLINDER = WORKFLOWS / "cylinder-dg-p2.toml"
BEAM = WORKFLOWS / "beam-dg-p2-3d.toml"


def _newton(out: Path) -> int:
    return json.loads((out / "summary.json").read_text())["newton_iterations"]


def _rows(part: str, scene: Path, sizes: dict[str, list[float]], quick: bool, workdir: Path, measure) -> list[dict]:
    """One run per method and size (only the first size with --quick); ``measure(record)`` gives the part's figure."""
    rows = []
    for method, hs in sizes.items():
        for h in hs[:1] if quick else hs:
            out = workdir / f"{part}-{method}-h{h:g}"
            r = _run(scene, method, h, out)
            rows.append({"part": part, "method": method, "h": h, "dofs": r["dofs"], **measure(r["record"]),
                         "newton_iterations": _newton(out), "plastic_points": r["record"]["plastic_points"],
                         "wall_time": r["wall_time"], "work_time": r["work_time"]})
    return rows


def _cylinder(quick: bool, workdir: Path) -> list[dict]:
    sizes = {"cg1": [0.1, 0.05, 0.025], "dg1": [0.1, 0.05, 0.025], "dg2": [0.1, 0.05]}
    return _rows("cylinder", CYLINDER, sizes, quick, workdir, lambda rec: {"error": rec["error_plastic_radius"]})


def _beam(quick: bool, workdir: Path) -> list[dict]:
    sizes = {"cg1": [0.5, 0.25, 0.125, 0.0625], "dg1": [0.5, 0.25], "dg2": [1.0, 0.5]}
    rows = _rows("beam", BEAM, sizes, quick, workdir, lambda rec: {"tip_deflection": -rec["probe_uz"]})
    ref = next(r["tip_deflection"] for r in reversed(rows) if r["method"] == "cg1")
    for r in rows:
        r["error"] = r["tip_deflection"] / ref - 1.0        # against the finest CG P1 run
    return rows


@register("dg-plastic")
def dg_plastic_bench(quick: bool, workdir: Path) -> list[dict]:
    """J2 plasticity: Hill's cylinder (2D) and a 3D cantilever past yield, CG P1 against DG P1 and DG P2."""
    workdir.mkdir(parents=True, exist_ok=True)
    return _cylinder(quick, workdir) + _beam(quick, workdir)
