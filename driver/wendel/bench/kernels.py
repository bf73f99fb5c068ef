"""Compiled element kernels against the FreeFEM-language forms (``wendel bench kernels``).

The step-42 ball (workflows/ball-indent.toml: contact + J2 plasticity, 3D P1) with PETSc-ML, once with
``numerics.assembly = "freefem"`` (the varf forms of lib/mechanics.idp and the Qh interpolations of
lib/plasticity.idp) and once with ``"compiled"`` (edp/plugins/wendel_kernels.cpp), interleaved in one run:
at 17k DoFs freefem, compiled, compiled, freefem; at 47k DoFs (not with --quick) freefem, compiled (about 2 minutes
on a quiet machine; the 119k rows of the README, 3 minutes each, are single rows, see below). Rows are those
of :func:`wendel.bench.petsc.measure` (wall seconds per Newton step by phase) plus, for each compiled row, the
ratio of assembly + constitutive update per Newton step of the freefem rows of the same size (their mean)
to its own; the Newton and Krylov iterations and the contact force must be equal. One row alone:
``python -m wendel.bench.kernels H ASSEMBLY [SOLVER]``.
"""

from __future__ import annotations

from pathlib import Path

from ..loop import RESULTS
from . import WORKFLOWS, register
from .petsc import measure


def _step(r: dict) -> float:
    return r["assembly_s_per_step"] + r["constitutive_s_per_step"]


def _ratios(rows: list[dict]) -> list[dict]:
    for r in rows:
        ref = [_step(f) for f in rows if f["h"] == r["h"] and f["assembly"] == "freefem"]
        r["assembly_constitutive_s_per_step"] = _step(r)
        r["speedup_vs_freefem"] = sum(ref) / len(ref) / _step(r) if ref and r["assembly"] != "freefem" else None
    return rows


@register("kernels")
def kernels(quick: bool, workdir: Path) -> list[dict]:
    """Ball with PETSc-ML, FreeFEM forms against compiled kernels, interleaved (see the module docstring)."""
    ball = WORKFLOWS / "ball-indent.toml"
    plan = [(0.2 if quick else 0.1, a) for a in ("freefem", "compiled", "compiled", "freefem")]
    if not quick:
        plan += [(0.07, "freefem"), (0.07, "compiled")]
    rows = [measure(ball, workdir / f"ball-h{h:g}-{a}-{i}", "petsc", h=h, assembly=a) for i, (h, a) in enumerate(plan)]
    return _ratios(rows)


def main(argv: list[str] | None = None) -> None:
    """One row: ``python -m wendel.bench.kernels H ASSEMBLY [SOLVER]`` (ball-indent; solver petsc by default)."""
    import sys

    a = sys.argv[1:] if argv is None else argv
    if len(a) < 2:
        sys.exit(main.__doc__)
    h, assembly = float(a[0]), a[1]
    solver = a[2] if len(a) > 2 else "petsc"
    out = RESULTS / "bench" / "work" / "kernels-rows" / f"ball-h{h:g}-{assembly}-{solver}"
    r = measure(WORKFLOWS / "ball-indent.toml", out, solver, h=h, assembly=assembly)
    print(" ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in r.items()))


if __name__ == "__main__":
    main()
