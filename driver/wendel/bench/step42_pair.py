"""deal.II's step-42 and wendel's ball in one run, interleaved (``wendel bench step42-pair``, opt-in).

deal.II: its own step-42 (Q1, one rank, global refinements: 5 = 107,811 DoFs; 4 = 14,739 with --quick) built
from Debian's libdeal.ii-doc. wendel: workflows/ball-indent.toml at h = 0.05 (119,016 DoFs; 0.1 = 17,490 with
--quick) with PETSc-ML and the compiled element kernels (``numerics.assembly = "compiled"``), its linear solves
once to ``solver_tol`` in every Newton step (``forcing = "fixed"``) and once inexact (``forcing = "ew"``, the
Eisenstat-Walker forcing term; the Newton tolerance is the same). Order: deal.II, wendel fixed, wendel ew,
deal.II, so that a change of the machine's load during the run falls on both codes.

Each row gives the whole-run wall time, the Newton steps, the time of the Newton steps' own work (deal.II: its
TimerOutput sections "Assembling", "Residual and lambda" and "Solve"; wendel: assembly, constitutive update and
linear solve from summary.json) per Newton step per DoF, and for wendel's rows the ratio to the mean of the
deal.II rows of the same run (both per-step-per-DoF and whole-run wall time).
"""

from __future__ import annotations

import re
from pathlib import Path

from . import WORKFLOWS, register
from .petsc import measure
from .step42 import _dealii_build, _dealii_run

DEALII_STEP_SECTIONS = ("Assembling", "Residual and lambda", "Solve")


def dealii_sections(stdout: str) -> dict[str, float]:
    """Wall seconds by TimerOutput section of the last summary table step-42 printed.

    >>> dealii_sections("| Assembling    |  9 |  12.5s |  30% |\\n| Solve  | 9 | 20s | 50% |")
    {'Assembling': 12.5, 'Solve': 20.0}
    """
    out: dict[str, float] = {}
    for line in stdout.splitlines():
        m = re.match(r"\|\s*([A-Za-z][^|]*?)\s*\|\s*\d+\s*\|\s*([0-9.eE+-]+)s\s*\|", line)
        if m:
            out[m.group(1)] = float(m.group(2))
    return out


def _dealii_row(exe: Path, folder: Path, refinements: int) -> dict:
    (r,) = _dealii_run(exe, folder, refinements, 1, "global", "sphere")
    sec = dealii_sections((folder / "stdout.txt").read_text())
    step = sum(sec.get(k, 0.0) for k in DEALII_STEP_SECTIONS)
    newton = max(r["newton_iterations"], 1)
    return {"code": "deal.II 9.4 step-42", "dofs": r["dofs"], "newton_iterations": r["newton_iterations"],
            "contact_force": r["contact_force"], "wall_time": r["wall_time_cumulative"],
            "step_s": step / newton, "us_per_newton_step_per_dof": 1e6 * step / newton / r["dofs"],
            "sections": sec}


def _wendel_row(out: Path, h: float, forcing: str, scene: Path = WORKFLOWS / "ball-indent.toml") -> dict:
    r = measure(scene, out, "petsc", h=h, assembly="compiled", forcing=forcing)
    step = r["assembly_s_per_step"] + r["constitutive_s_per_step"] + r["solve_s_per_step"]
    return {"code": f"wendel (PETSc-ML, compiled kernels, forcing {forcing})", "dofs": r["dofs"],
            "krylov_per_step": r["krylov_per_step"], "petsc_setups": r["petsc_setups"],
            "newton_iterations": r["newton_iterations"], "contact_force": r["contact_force"],
            "wall_time": r["wall_time"], "step_s": step, "us_per_newton_step_per_dof": 1e6 * step / r["dofs"]}


def ratios(rows: list[dict]) -> list[dict]:
    """wendel's rows against the mean of the deal.II rows of the same run."""
    d = [r for r in rows if r["code"].startswith("deal.II")]
    per_dof = sum(r["us_per_newton_step_per_dof"] for r in d) / len(d)
    wall = sum(r["wall_time"] for r in d) / len(d)
    for r in rows:
        if not r["code"].startswith("deal.II"):
            r["step_per_dof_vs_dealii"] = r["us_per_newton_step_per_dof"] / per_dof
            r["wall_time_vs_dealii"] = r["wall_time"] / wall
    return rows


@register("step42-pair")
def step42_pair(quick: bool, workdir: Path) -> list[dict]:
    """deal.II step-42 and the wendel ball, interleaved D, W (fixed), W (ew), D (see the module docstring)."""
    exe = _dealii_build(workdir)
    refinements, h = (4, 0.1) if quick else (5, 0.05)
    rows = [_dealii_row(exe, workdir / "dealii-0", refinements),
            _wendel_row(workdir / "wendel-1", h, "fixed"),
            _wendel_row(workdir / "wendel-2", h, "ew"),
            _dealii_row(exe, workdir / "dealii-3", refinements)]
    for r in rows:
        r.pop("sections", None)
    return ratios(rows)
