"""Time to a contact force within 2 % of the converged one: deal.II's adaptive step-42 against the wendel ball
(``wendel bench step42-accuracy``, opt-in; about 10 minutes under the lock).

Issue 19 asks for the ball's contact force within 2 % of the converged value in at most 0.3x the wall time
deal.II's adaptive run needs to get there. The converged value is not known in closed form; both codes converge
from above (README "deal.II step-42"): their finest forces are 55.81 (wendel, 225,897 DoFs) and 55.84 (deal.II,
adaptive cycle 4, 154,647 DoFs), and three-point Richardson fits through wendel's forces at h = 0.1 / 0.07 /
0.05 / 0.04 give 54.0 to 55.4 depending on the triple. ``F_REF`` = 55.0 (the issue's "about 55", inside that
range) is the converged value here; every row also gives its distance from it, so another estimate can be
applied to the same rows.

Order: wendel with an empty mesh cache (cold: gmsh meshes, the mesh is stored), deal.II's adaptive run
(3 initial refinements, 5 cycles, refinement by percentage: its README rows; one row per cycle with the
cumulative wall time), wendel with the cache the cold run filled (warm), and wendel cold once more with
``geometry.optimize = false`` (gmsh without its Netgen optimization: another, faster mesh, somewhat stiffer,
so at h = ``H_FAST``), and cold with ``geometry.algorithm = "hxt"`` and ``optimize = false`` too (gmsh's HXT
instead of its Delaunay: meshing 0.9-1.3 s instead of 11-13 s at these sizes; at h = ``H_HXT``). wendel: workflows/ball-indent.toml at
h = ``H`` with PETSc-ML, the compiled kernels and the inexact Newton (the step42-pair "forcing ew" row);
``WENDEL_ACCURACY_H``, ``WENDEL_ACCURACY_H_FAST`` and ``WENDEL_ACCURACY_H_HXT`` override them. deal.II's time to 2 % is the cumulative wall time of its first cycle within
2 % of ``F_REF``; each wendel row's ratio is its whole-run wall time (gmsh and output included) over that time.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from . import WORKFLOWS, register
from .meshcache import _cached_row
from .step42 import _dealii_build, _dealii_run

F_REF = 55.0          # the converged contact force taken here (see the module docstring)
BAND = 0.02           # within 2 %
H = 0.045             # m: wendel's mesh size at the ball (h / 8 at the contact)
H_FAST = 0.042        # m: the same without Netgen (at 0.045 its force is 2.1 % above F_REF, measured)
H_HXT = 0.040         # m: HXT without Netgen (at 0.045 its force is 2.5 % above F_REF, at 0.040 1.96 %, measured)


def within(force: float) -> bool:
    """The force within ``BAND`` of ``F_REF``.

    >>> within(56.0), within(56.19), within(54.0)
    (True, False, True)
    """
    return abs(force - F_REF) <= BAND * F_REF


@register("step42-accuracy")
def step42_accuracy(quick: bool, workdir: Path) -> list[dict]:
    """wendel cold, deal.II adaptive (per cycle), wendel warm (see the module docstring)."""
    exe = _dealii_build(workdir)
    h = 0.1 if quick else float(os.environ.get("WENDEL_ACCURACY_H", H))
    cycles = 2 if quick else 5
    cache = workdir / "cache"
    shutil.rmtree(cache, ignore_errors=True)
    cold = _cached_row(workdir / "wendel-cold", h, cache)
    dealii = _dealii_run(exe, workdir / "dealii-adaptive", 3, cycles, "percentage", "sphere")
    warm = _cached_row(workdir / "wendel-warm", h, cache)
    fast_scene = workdir / "ball-indent-no-netgen.toml"
    text = (WORKFLOWS / "ball-indent.toml").read_text()
    fast_scene.write_text(text.replace('builder = "box"\n', 'builder = "box"\noptimize = false\n', 1))
    h_fast = 0.1 if quick else float(os.environ.get("WENDEL_ACCURACY_H_FAST", H_FAST))
    fast = _cached_row(workdir / "wendel-no-netgen", h_fast, cache, scene=fast_scene)
    fast["code"] += ", geometry.optimize = false"
    hxt_scene = workdir / "ball-indent-hxt.toml"
    hxt_scene.write_text(text.replace('builder = "box"\n', 'builder = "box"\noptimize = false\nalgorithm = "hxt"\n', 1))
    h_hxt = 0.1 if quick else float(os.environ.get("WENDEL_ACCURACY_H_HXT", H_HXT))
    hxt = _cached_row(workdir / "wendel-hxt", h_hxt, cache, scene=hxt_scene)
    hxt["code"] += ', geometry.algorithm = "hxt", optimize = false'
    reached = [r for r in dealii if within(r["contact_force"])]
    t_ref = reached[0]["wall_time_cumulative"] if reached else None
    rows = []
    for r in dealii:
        rows.append({"code": f"deal.II 9.4 step-42 adaptive, cycle {r['cycle']}", "dofs": r["dofs"],
                     "newton_iterations": r["newton_iterations"], "contact_force": r["contact_force"],
                     "wall_time": r["wall_time_cumulative"]})
    cold["h"] = warm["h"] = h
    fast["h"], hxt["h"] = h_fast, h_hxt
    for r in (cold, warm, fast, hxt):
        r["wall_time_vs_dealii_to_2pct"] = r["wall_time"] / t_ref if t_ref else None
        rows.append(r)
    for r in rows:
        r["off_reference"] = r["contact_force"] / F_REF - 1.0
        r["within_2pct"] = within(r["contact_force"])
    return rows
