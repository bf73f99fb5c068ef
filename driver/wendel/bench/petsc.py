"""PETSc against Jacobi-CG on the project's own Newton matrices (``wendel bench petsc``).

The step-42 ball (workflows/ball-indent.toml: contact + plasticity, graded gmsh meshes) at 17k DoFs with
``solver = "cg"`` (Jacobi-CG in the FreeFEM language, masked constraint rows) and ``solver = "petsc"`` with each
preconditioner preset, ML without the kept preconditioner and ML on 2 ranks; at 47k DoFs with CG, ML and GAMG;
then the other scenes that use CG (hertz-3d, stamp-indent) with CG and the default preset. Rows give wall
seconds per Newton step of the linear solve (CSR conversion, preconditioner setup and Krylov iterations
included), of the assembly (and of the tangent matrix alone) and of the constitutive update, the Krylov
iterations per Newton step, the Newton iterations, the contact force (which must not depend on the solver) and
the CPU time of the FreeFEM processes for the whole run (the steadier figure on a shared machine). One row
alone: ``python -m wendel.bench.petsc SCENE H SOLVER [PC [REUSE [RANKS [OPTIONS [ASSEMBLY [FORCING]]]]]]``.
"""

from __future__ import annotations

import json
import resource
import shutil
from pathlib import Path

from ..loop import RESULTS, run_scene
from ..scene import load
from . import WORKFLOWS, register

DEFAULT_PC = "ml"


def measure(scene_path: Path, out: Path, solver: str, pc: str = DEFAULT_PC, reuse: bool = True,
            h: float | None = None, options: str = "", ranks: int = 1, assembly: str = "freefem",
            forcing: str = "fixed") -> dict:
    """Run one scene with one solver; return its row (wall times per Newton step by phase, CPU time of the
    FreeFEM processes for the whole run: on a shared machine the steadier figure)."""
    scene = load(scene_path)
    if h is not None:
        scene.geometry.h = h
    scene.numerics.solver = solver
    scene.numerics.ranks = ranks                 # after the solver: the scene check ties ranks to it
    scene.numerics.petsc.pc = pc
    scene.numerics.petsc.reuse = reuse
    scene.numerics.petsc.options = options
    scene.numerics.assembly = assembly
    scene.numerics.forcing = forcing
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
            "solver": solver if solver != "petsc" else f"petsc-{pc}" + ("" if reuse else "-noreuse"), "ranks": ranks,
            "assembly": assembly, "forcing": forcing,
            "newton_iterations": s["newton_iterations"],
            "krylov_per_step": last["linear_iterations"] / newton,
            "solve_s_per_step": ph["linear_solve"] / newton,
            "assembly_s_per_step": ph["assembly"] / newton,
            "tangent_s_per_step": last.get("time_tangent", 0.0) / newton,
            "constitutive_s_per_step": ph["constitutive"] / newton,
            "petsc_setup_s_per_step": last.get("time_petsc_setup", 0.0) / newton,
            "petsc_krylov_s_per_step": last.get("time_petsc_krylov", 0.0) / newton,
            "petsc_setups": last.get("petsc_setups"),
            "contact_force": last.get("contact_force"), "wall_time": s["wall_time"], "cpu_time": cpu}


def _speedups(rows: list[dict]) -> list[dict]:
    """Each row's solve time per Newton step against CG's on the same scene and size."""
    cg = {(r["scene"], r["h"]): r for r in rows if r["solver"] == "cg"}
    for r in rows:
        ref = cg.get((r["scene"], r["h"]))
        r["solve_speedup_vs_cg"] = ref["solve_s_per_step"] / r["solve_s_per_step"] if ref else None
        r["cpu_ratio_vs_cg"] = r["cpu_time"] / ref["cpu_time"] if ref else None
    return rows


@register("petsc")
def petsc(quick: bool, workdir: Path) -> list[dict]:
    """Ball at 17k DoFs with CG and each PETSc preset (and ML without the kept preconditioner, and on 2
    ranks), at 47k with CG, ML and GAMG; hertz-3d and stamp with CG and the default preset."""
    ball = WORKFLOWS / "ball-indent.toml"
    h1 = 0.2 if quick else 0.1
    rows = [measure(ball, workdir / f"ball-h{h1:g}-cg", "cg", h=h1)]
    for pc in ("ml", "gamg", "hypre"):
        rows.append(measure(ball, workdir / f"ball-h{h1:g}-{pc}", "petsc", pc=pc, h=h1))
    rows.append(measure(ball, workdir / f"ball-h{h1:g}-ml-noreuse", "petsc", pc="ml", reuse=False, h=h1))
    rows.append(measure(ball, workdir / f"ball-h{h1:g}-ml-np2", "petsc", pc="ml", h=h1, ranks=2))
    if not quick:
        for solver, pc in (("cg", DEFAULT_PC), ("petsc", "ml"), ("petsc", "gamg")):
            rows.append(measure(ball, workdir / f"ball-h0.07-{solver}-{pc}", solver, pc=pc, h=0.07))
    for name in ("hertz-3d", "stamp-indent"):
        path = WORKFLOWS / f"{name}.toml"
        h = 0.2 if quick else None
        for solver in ("cg", "petsc"):
            rows.append(measure(path, workdir / f"{name}-{solver}", solver, h=h))
    return _speedups(rows)


def main(argv: list[str] | None = None) -> None:
    """One row of the bench (each row is a run of up to a few minutes; the machine may be shared):
    ``python -m wendel.bench.petsc SCENE H SOLVER [PC [REUSE [RANKS [OPTIONS [ASSEMBLY [FORCING]]]]]]``, e.g.
    ``python -m wendel.bench.petsc ball-indent 0.07 petsc ml``."""
    import sys

    a = sys.argv[1:] if argv is None else argv
    if len(a) < 3:
        sys.exit(main.__doc__)
    scene, h, solver = a[0], float(a[1]), a[2]
    pc = a[3] if len(a) > 3 else DEFAULT_PC
    reuse = a[4] != "0" if len(a) > 4 else True
    ranks = int(a[5]) if len(a) > 5 else 1
    options = a[6] if len(a) > 6 else ""
    assembly = a[7] if len(a) > 7 else "freefem"
    forcing = a[8] if len(a) > 8 else "fixed"
    out = (RESULTS / "bench" / "work" / "petsc-rows"
           / f"{scene}-h{h:g}-{solver}-{pc}-{int(reuse)}-np{ranks}-{assembly}-{forcing}")
    r = measure(WORKFLOWS / f"{scene}.toml", out, solver, pc=pc, reuse=reuse, h=h, options=options, ranks=ranks,
                assembly=assembly, forcing=forcing)
    print(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in r.items()))


if __name__ == "__main__":
    main()
