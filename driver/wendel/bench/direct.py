"""``wendel bench direct``: the direct solver's factorization, FreeFEM's UMFPACK64 against MUMPS's LU through
wendel's PETSc plugin (``numerics.direct = "mumps"``), interleaved in one run.

Cases: the steel cut's first 120 um (24 increments of 5 um, remeshed every 8) at edge r/2 with F-bar and
conduction (friction makes its Newton matrix unsymmetric, F-bar gives it 36 entries a row: 3,700 unknowns),
``ul-necking-bar`` (2D F-bar plasticity, 70 increments) and ``hertz-force-3d`` (3D contact) at their default sizes,
each once with each factorization, the two one after the other. Rows: wall time, the linear-solve phase per Newton
iteration (summary.json's ``wall_time_by_phase``; it holds the heat equation's solve too in the cut), Newton
iterations, the CPU time of the FreeFEM processes (the steadier figure on a shared machine) and a result that
must not depend on the solver (the cut's last F_c, the bar's and the ball's force); ``solve_ratio``: MUMPS's solve
per iteration over UMFPACK64's. The cut is path-dependent through its step cuts and remeshes: a round-off
difference may cut another step, so its iterations may differ. ``--quick``: the cut's first 40 um only."""

from __future__ import annotations

import csv
import json
import resource
import shutil
from pathlib import Path

from ..loop import run_scene
from ..scene import load
from . import WORKFLOWS, register

LIBS = ("umfpack", "mumps")


def cut_scene(steps: int):
    """The steel cut's first ``steps`` increments of 5 um at edge r/2 with F-bar and conduction (also
    ``cutting-levers``'s)."""
    from .cutting_mesh import _scene
    scene = _scene(2, 1, quick=False, vol="fbar")
    scene.thermal.coupling = "staggered"
    scene.cutting.cut_length = steps * 5e-6
    scene.loading.steps = steps
    return scene


def _run(name: str, lib: str, quick: bool, out: Path) -> dict:
    shutil.rmtree(out, ignore_errors=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    if name == "cut":
        from ..cutting.fe_run import run_cut
        scene = cut_scene(8 if quick else 24)
        scene.numerics.direct = lib
        root = run_cut(scene, WORKFLOWS / "cutting-aisi1045.toml", out, smoke=False, progress=lambda *_: None,
                       frames=False)
        result = float(list(csv.DictReader((root / "cutting.csv").open()))[-1]["Fc_N"])
    else:
        path = WORKFLOWS / f"{name}.toml"
        scene = load(path)
        scene.numerics.direct = lib
        scene.output.png = False
        root = run_scene(scene, path, out, progress=lambda *_: None)
        result = None
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    s = json.loads((root / "summary.json").read_text())
    last, ph = s["last_increment"], s["wall_time_by_phase"]
    if result is None:
        result = last.get("contact_force") or last.get("reaction_x_1") or last.get("max_von_mises")
    newton = max(s["newton_iterations"], 1)
    return {"case": name, "direct": lib, "dofs": s["dofs"], "increments": s["increments"],
            "newton_iterations": s["newton_iterations"], "wall_s": s["wall_time"],
            "solve_s_per_iteration": ph["linear_solve"] / newton, "assembly_s_per_iteration": ph["assembly"] / newton,
            "cpu_s": (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime), "result": result}


@register("direct")
def direct_bench(quick: bool, workdir: Path) -> list[dict]:
    rows = []
    for name in ("cut", "ul-necking-bar", "hertz-force-3d"):
        pair = {lib: _run(name, lib, quick, workdir / f"{name}-{lib}") for lib in LIBS}
        u, m = pair["umfpack"], pair["mumps"]
        m["solve_ratio"] = m["solve_s_per_iteration"] / u["solve_s_per_iteration"]
        m["cpu_ratio"] = m["cpu_s"] / u["cpu_s"]
        m["result_change"] = m["result"] / u["result"] - 1
        rows += [u, m]
    return rows
