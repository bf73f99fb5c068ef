"""Benchmark of 3D interior penalty DG against continuous P1 (``wendel bench dg-3d``).

Two parts, one row per run (same machine, same launch path):

* ``cantilever``: the 10 x 1 x 1 m beam of workflows/cantilever-dg-3d.toml (clamped, 1 MN shear on its end) at
  nu = 0.3 and nu = 0.4999: tip deflection u_z(10, 0.5, 0.5) of CG P1, DG P1 and DG P2 against Timoshenko's
  beam (:func:`timoshenko`), with DoFs and wall time; at nu = 0.4999 CG P1 locks;
* ``mms``: the manufactured solution of workflows/dg-mms-3d.toml with DG P1 and DG P2 on two meshes each (h and
  h/2): L2 and broken-H1 errors and their observed rates.
"""

from __future__ import annotations

import math
from pathlib import Path

from . import WORKFLOWS, register
from .dg import _run

CANTILEVER = WORKFLOWS / "cantilever-dg-3d.toml"
MMS = WORKFLOWS / "dg-mms-3d.toml"


def timoshenko(nu: float, E: float = 200e9, P: float = 1e6, L: float = 10.0, b: float = 1.0) -> float:
    """Tip deflection (m) of a Timoshenko cantilever of square section b x b under the end load P.

    P L^3 / (3 E I) + P L / (k G A), k = 10 (1 + nu) / (12 + 11 nu) (Cowper 1966, rectangle).

    >>> round(timoshenko(0.3), 6)
    0.020153
    """
    inertia, area = b ** 4 / 12.0, b * b
    shear = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu) * E / (2.0 * (1.0 + nu)) * area
    return P * L ** 3 / (3.0 * E * inertia) + P * L / shear


def _cantilever(quick: bool, workdir: Path) -> list[dict]:
    from ..scene import load

    rows = []
    for nu in (0.3, 0.4999):
        scene_nu = workdir / f"cantilever-nu{nu}.toml"
        text = CANTILEVER.read_text().replace("nu = 0.3 ", f"nu = {nu} ")
        scene_nu.parent.mkdir(parents=True, exist_ok=True)
        scene_nu.write_text(text)
        assert load(scene_nu).material.nu == nu
        ref = timoshenko(nu)
        sizes = {"cg1": [1.0, 0.5, 0.25], "dg1": [1.0, 0.5], "dg2": [1.0, 0.5]}
        for method, hs in sizes.items():
            for h in hs[:2] if quick else hs:
                if quick and method == "dg2" and h < 1.0:
                    continue
                r = _run(scene_nu, method, h, workdir / f"cantilever-{nu}-{method}-{h:g}")
                uz = -r["record"]["probe_uz"]
                rows.append({"part": "cantilever", "nu": nu, "method": method, "h": h, "dofs": r["dofs"],
                             "tip_deflection": uz, "reference": ref, "error": uz / ref - 1.0,
                             "wall_time": r["wall_time"], "work_time": r["work_time"]})
    return rows


def _mms(quick: bool, workdir: Path) -> list[dict]:
    rows = []
    for method, h0 in (("dg1", 0.25), ("dg2", 0.5)):
        prev = None
        for h in (h0, h0 / 2):
            if quick and method == "dg2" and h < h0:
                continue
            r = _run(MMS, method, h, workdir / f"mms-{method}-{h:g}")
            rec = r["record"]
            el2 = rec["error_l2"] / rec["reference_l2"]
            eh1 = rec["error_h1"] / rec["reference_h1"]
            row = {"part": "mms", "method": method, "h": h, "dofs": r["dofs"], "error_l2": el2, "error_h1": eh1,
                   "wall_time": r["wall_time"], "work_time": r["work_time"]}
            if prev is not None:
                ratio = math.log(prev["h"] / h)
                row["rate_l2"] = math.log(prev["error_l2"] / el2) / ratio
                row["rate_h1"] = math.log(prev["error_h1"] / eh1) / ratio
                # gmsh's unstructured tetrahedra do not halve exactly: the rate in the DoFs' length scale
                dofs_ratio = math.log(r["dofs"] / prev["dofs"]) / 3.0
                row["rate_l2_dofs"] = math.log(prev["error_l2"] / el2) / dofs_ratio
                row["rate_h1_dofs"] = math.log(prev["error_h1"] / eh1) / dofs_ratio
            rows.append(row)
            prev = row
    return rows


@register("dg-3d")
def dg3d_bench(quick: bool, workdir: Path) -> list[dict]:
    """The 3D cantilever (CG P1, DG P1, DG P2 at two Poisson ratios) and the 3D manufactured solution."""
    workdir.mkdir(parents=True, exist_ok=True)
    return _cantilever(quick, workdir) + _mms(quick, workdir)
