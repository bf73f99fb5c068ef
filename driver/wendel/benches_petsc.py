"""PETSc against Jacobi-CG on the project's own Newton matrices (``wendel bench petsc``).

The step-42 ball (workflows/ball-indent.toml: contact + plasticity, graded gmsh meshes) at growing sizes,
with ``solver = "cg"`` (Jacobi-CG in the FreeFEM language, masked constraint rows) and ``solver = "petsc"``
with each preconditioner preset, the kept preconditioner switched off once for GAMG; then the other scenes
that use CG (hertz-3d, stamp-indent) with CG and the default PETSc preset. Rows give the seconds per Newton
step of the linear solve (CSR conversion, preconditioner setup and Krylov iterations included), of the
assembly and of the constitutive update, the Krylov iterations per Newton step, the Newton iterations and
the contact force (which must not depend on the solver). One FreeFEM process per row, one rank.
"""

from __future__ import annotations

import json
import resource
import shutil
from pathlib import Path

from .bench import WORKFLOWS, register
from .run import run_scene
from .scene import load

DEFAULT_PC = "gamg"


def measure(scene_path: Path, out: Path, solver: str, pc: str = DEFAULT_PC, reuse: bool = True,
            h: float | None = None, options: str = "") -> dict:
    """Run one scene with one solver; return its row."""
    scene = load(scene_path)
    if h is not None:
        scene.geometry.h = h
    scene.numerics.solver = solver
    scene.numerics.petsc.pc = pc
    scene.numerics.petsc.reuse = reuse
    scene.numerics.petsc.options = options
    scene.output.png = False
    scene.output.vtu = False
    shutil.rmtree(out, ignore_errors=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    root = run_scene(scene, scene_path, out, progress=lambda *_: None)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    s = json.loads((root / "summary.json").read_text())
    last, ph = s["last_increment"], s["wall_time_by_phase"]
    newton = max(s["newton_iterations"], 1)
    return {"scene": scene_path.stem, "h": scene.geometry.h, "dofs": s["dofs"],
            "solver": solver if solver != "petsc" else f"petsc-{pc}" + ("" if reuse else "-noreuse"),
            "newton_iterations": s["newton_iterations"],
            "krylov_per_step": last["linear_iterations"] / newton,
            "solve_s_per_step": ph["linear_solve"] / newton,
            "assembly_s_per_step": ph["assembly"] / newton,
            "constitutive_s_per_step": ph["constitutive"] / newton,
            "petsc_setup_s_per_step": last.get("time_petsc_setup", 0.0) / newton,
            "petsc_krylov_s_per_step": last.get("time_petsc_krylov", 0.0) / newton,
            "petsc_setups": last.get("petsc_setups"),
            "contact_force": last.get("contact_force"), "wall_time": s["wall_time"], "cpu_time": cpu}


def _speedups(rows: list[dict]) -> list[dict]:
    """Each row's solve time per Newton step against CG's on the same scene and size."""
    cg = {(r["scene"], r["h"]): r["solve_s_per_step"] for r in rows if r["solver"] == "cg"}
    for r in rows:
        ref = cg.get((r["scene"], r["h"]))
        r["solve_speedup_vs_cg"] = ref / r["solve_s_per_step"] if ref and r["solve_s_per_step"] else None
    return rows


@register("petsc")
def petsc(quick: bool, workdir: Path) -> list[dict]:
    """Ball at 3k/17k/47k DoFs with CG and each PETSc preset; hertz-3d and stamp with CG and the default."""
    ball = WORKFLOWS / "ball-indent.toml"
    rows = []
    for h in ([0.2] if quick else [0.2, 0.1, 0.07]):
        rows.append(measure(ball, workdir / f"ball-h{h:g}-cg", "cg", h=h))
        for pc in ("gamg", "hypre", "ml"):
            rows.append(measure(ball, workdir / f"ball-h{h:g}-{pc}", "petsc", pc=pc, h=h))
        rows.append(measure(ball, workdir / f"ball-h{h:g}-gamg-noreuse", "petsc", pc="gamg", reuse=False, h=h))
    for name in ("hertz-3d", "stamp-indent"):
        path = WORKFLOWS / f"{name}.toml"
        h = 0.2 if quick else None
        for solver in ("cg", "petsc"):
            rows.append(measure(path, workdir / f"{name}-{solver}", solver, h=h))
    return _speedups(rows)
