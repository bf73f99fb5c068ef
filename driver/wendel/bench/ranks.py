"""1 rank against 2 ranks on the step-42 ball (``wendel bench ranks``, opt-in; about 4 minutes under the lock).

workflows/ball-indent.toml at h = 0.05 (119,016 DoFs; 0.1 = 17,490 with --quick), PETSc-ML, compiled kernels
(on 2 ranks each rank assembles its own slab of tetrahedra: rank-local assembly), inexact Newton, with a warm
mesh cache (a first untimed run fills it), so that the gmsh meshing is out of both. Then 1, 2, 1, 2 ranks
interleaved. Each row gives the wall seconds of the whole run and of its phases (summary.json), per Newton step
the assembly, constitutive update and linear solve (PETSc setup and Krylov), the Krylov iterations per step, the
contact force and the CPU time of the FreeFEM processes; a 2-rank row also its speed-up against the 1-rank row
before it (whole run and per Newton step: assembly + constitutive + solve). One row alone:
``WENDEL_MESH_CACHE=DIR python -m wendel.bench.petsc ball-indent 0.05 petsc ml 1 R "" compiled ew``.
"""

from __future__ import annotations

import json
from pathlib import Path

from ..meshes.cache import ENV
from . import WORKFLOWS, environ, register
from .petsc import measure

PHASES = ("mesh", "freefem_startup", "assembly", "constitutive", "linear_solve", "freefem_output", "freefem_other",
          "failed_increments", "driver_output")


def _row(out: Path, h: float, ranks: int) -> dict:
    r = measure(WORKFLOWS / "ball-indent.toml", out, "petsc", pc="ml", h=h, ranks=ranks, assembly="compiled",
                forcing="ew")
    s = json.loads((out / "summary.json").read_text())
    row = {k: r[k] for k in ("ranks", "dofs", "newton_iterations", "krylov_per_step", "contact_force", "wall_time",
                             "cpu_time", "assembly_s_per_step", "constitutive_s_per_step", "solve_s_per_step",
                             "petsc_setup_s_per_step", "petsc_krylov_s_per_step", "tangent_s_per_step")}
    row["step_s"] = r["assembly_s_per_step"] + r["constitutive_s_per_step"] + r["solve_s_per_step"]
    row["local_tets"] = s["last_increment"].get("petsc_local_tets", 0)
    row["active_set_s"] = s["last_increment"].get("time_active_set", 0.0)     # contact rows (part of assembly)
    row["elements"] = s["elements"]
    for p in PHASES:
        row[f"{p}_s"] = s["wall_time_by_phase"].get(p, 0.0)
    row["cache_hit"] = s.get("mesh_cache", {}).get("hit")
    return row


@register("ranks")
def ranks(quick: bool, workdir: Path) -> list[dict]:
    """A cache-filling run, then 1, 2, 1, 2 ranks (see the module docstring)."""
    h = 0.1 if quick else 0.05
    with environ(**{ENV: str(workdir / "cache")}):
        _row(workdir / "fill", h, 1)
        rows = [_row(workdir / f"run{i}-np{n}", h, n) for i, n in enumerate((1, 2, 1, 2))]
    for one, two in zip(rows[0::2], rows[1::2]):
        assert abs(two["contact_force"] - one["contact_force"]) <= 1e-7 * abs(one["contact_force"]), \
            "2 ranks must give the 1-rank force"
        two["speedup_whole"] = one["wall_time"] / two["wall_time"]
        two["speedup_step"] = one["step_s"] / two["step_s"]
    return rows
