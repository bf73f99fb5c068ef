"""Benchmark of 3D interior penalty DG against continuous P1 (``wendel bench dg-3d``).

The 10 x 1 x 1 m beam of workflows/cantilever-dg-3d.toml (clamped, 1 MN shear on its end) at nu = 0.3 and
nu = 0.4999: tip deflection u_z(10, 0.5, 0.5) of CG P1, DG P1 and DG P2 against Timoshenko's beam
(:func:`timoshenko`), with DoFs and wall time, one row per run; at nu = 0.4999 CG P1 locks. (The 3D
manufactured solution's rates: ``wendel study workflows/dg-mms-3d.toml``, ``dg-mms-3d-p2.toml``.)
"""

from __future__ import annotations

from pathlib import Path

from . import WORKFLOWS, register
from .dg import _run

CANTILEVER = WORKFLOWS / "cantilever-dg-3d.toml"


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
        # DG P2 at h = 0.5 (72k DoFs, about a minute) only where CG locks
        sizes = {"cg1": [1.0, 0.5, 0.25, 0.125], "dg1": [1.0, 0.5, 0.25], "dg2": [1.0, 0.5] if nu > 0.4 else [1.0]}
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


@register("dg-3d")
def dg3d_bench(quick: bool, workdir: Path) -> list[dict]:
    """The 3D cantilever (CG P1, DG P1, DG P2 at two Poisson ratios) and the 3D manufactured solution."""
    workdir.mkdir(parents=True, exist_ok=True)
    return _cantilever(quick, workdir)
