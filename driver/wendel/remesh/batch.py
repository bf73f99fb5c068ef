"""Which increments one FreeFEM launch runs in a remeshing run (issue 20): a whole remeshing segment.

Without this a remeshing run launched FreeFEM once per increment so that the driver could judge the mesh
after each; FreeFEM's start-up was then most of the run (upsetting at smoke size: 10.3 s of 17 s, 11
launches). Now FreeFEM judges the deformed mesh after each increment itself (``edp/lib/remeshstop.idp``,
``-DREMESHSTOP=1``, plane meshes on one rank) and ends the launch after a poor one; a launch also ends after
an increment of ``remesh.at``. The driver judges every increment again (:func:`wendel.remesh.step.judge`)
and stays the authority: :func:`roll_back` drops increments that FreeFEM ran past a mesh the driver finds
poor, so that the run is the same as one launch per increment.
"""

from __future__ import annotations

import shutil

STOP_FILE = "remesh-stop.txt"
"""Written by FreeFEM into the fem folder when it ends a launch for remeshing (the increment number)."""


def inside_freefem(scene, dimension: int) -> bool:
    """Whether FreeFEM can end a launch at a poor mesh: plane P1 meshes on one rank (the measure in
    remeshstop.idp is that of triangles; several ranks would have to agree)."""
    from ..loop.launch import ELEMENT

    return dimension == 2 and scene.numerics.ranks == 1 and ELEMENT == "P1"


def first_steps(scene, lf: float, pending: list[float]) -> list[float]:
    """The load factors a remesh puts before the next one, after its re-equilibration at ``lf``
    (``remesh.first_step`` f < 1: lf + f d, lf + 2 f d, ... below lf + d, d the step to ``pending[0]``). Measured on
    the FE cut (README, session 24): the first forward step on a new mesh converged at 1/16-1/2 of the step, never
    whole, after one to four failed tries."""
    if not pending or scene.loading.adaptive:
        return []
    return [lf + s * (pending[0] - lf) for s in ramp(scene.remesh.first_step)]


def ramp(f: float) -> list[float]:
    """The shares of a step that :func:`first_steps` takes before the whole: f, 2 f, 4 f, ... below 1.

    >>> ramp(0.25), ramp(0.3), ramp(1.0)
    ([0.25, 0.5], [0.3, 0.6], [])
    """
    out = []
    while f < 1 - 1e-9:
        out.append(f)
        f *= 2
    return out


def plan(scene, state, dimension: int) -> tuple[list[float], list[str]]:
    """The load factors of the next launch and its extra FreeFEM arguments.

    >>> from types import SimpleNamespace as NS
    >>> remesh = NS(min_quality=0.2, at=[5], max_remeshes=3)
    >>> scene = NS(remesh=remesh, loading=NS(adaptive=False), numerics=NS(ranks=1))
    >>> state = NS(pending=[0.1 * k for k in range(3, 9)], last=(2, 0.2), reequilibrate=False, remeshes=[])
    >>> loads, args = plan(scene, state, 2); len(loads), args      # increments 3, 4, 5: remesh.at stops at 5
    (3, ['-DREMESHSTOP=1', '-remesh_min_quality', '0.2'])
    >>> len(plan(scene, state, 3)[0])                               # 3D: one increment per launch
    1
    >>> state.reequilibrate = True; plan(scene, state, 2)[1][-2:]   # no stop after the re-equilibration
    ['-remesh_skip', '3']
    """
    r = scene.remesh
    if scene.loading.adaptive:
        return state.pending[:1], []            # the step is chosen after every increment
    if r is None or len(state.remeshes) >= r.max_remeshes:
        return list(state.pending), []          # no remeshing (any more): one launch for every increment
    if not inside_freefem(scene, dimension):
        return state.pending[:1], []            # the driver judges the mesh after every increment
    inc0 = state.last[0] + 1
    n = len(state.pending)
    forced = [a for a in r.at if a >= inc0]
    if forced:
        n = min(n, min(forced) - inc0 + 1)
    args = ["-DREMESHSTOP=1", "-remesh_min_quality", repr(float(r.min_quality))]
    if state.reequilibrate:     # the re-equilibration on a new mesh is never judged (as before): no stop there
        args += ["-remesh_skip", str(inc0)]
    return state.pending[:n], args


def stopped_at(fem) -> int | None:
    """The increment after which FreeFEM ended the launch for remeshing, if it did."""
    try:
        return int((fem / STOP_FILE).read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def settle(scene, files, state, dimension: int, first: int, progress) -> bool:
    """After a launch with stops from increment ``first`` on: roll back what ran past a mesh the driver finds
    poor (what failed there too is solved again after the remesh); return whether the launch ended short on
    purpose (stopped for remeshing, or rolled back)."""
    dropped = roll_back(scene, files, state, first) if state.accepted else []
    if dropped:
        from ..loop.checkpoint import save

        save(files, scene, state, dimension)
        progress(f"  increments {dropped[0]}-{dropped[-1]} dropped: the mesh was poor before them")
    return bool(dropped) or (bool(state.accepted) and stopped_at(files.fem) == state.last[0])


def roll_back(scene, files, state, first: int) -> list[int]:
    """Drop the increments accepted after the first one of this launch (from ``first`` on) whose mesh the
    driver finds poor: their load factors are pending again. Returns the dropped increments."""
    r = scene.remesh
    if len(state.remeshes) >= r.max_remeshes:
        return []
    reeq = state.segments[-1]["first"] if len(state.segments) > 1 else None
    mine = [i for i, _ in state.accepted if i >= first and i != reeq]
    poor = [i for i in mine if state.quality.get(i, {}).get("min_quality", 1.0) < r.min_quality
            or state.quality.get(i, {}).get("inverted", 0) > 0 or i in r.at]
    if not poor or poor[0] == state.last[0]:
        return []
    dropped = forget(scene, files, state, poor[0])
    state.pending[:0] = [lf for _, lf in dropped]
    return [i for i, _ in dropped]


def forget(scene, files, state, keep: int) -> list[tuple[int, float]]:
    """Drop the accepted increments after ``keep`` with their files (increment folder, VTU, history and Newton
    rows, the .pvd's entries), and from the counts of the launches that accepted them (the last ones that did);
    returns them (number, load factor)."""
    from ..results import summary, vtu

    dropped = [(i, lf) for i, lf in state.accepted if i > keep]
    state.accepted = [(i, lf) for i, lf in state.accepted if i <= keep]
    left = len(dropped)
    for launch in reversed(state.launches):
        take = min(left, launch["increments"])
        launch["increments"], left = launch["increments"] - take, left - take
        if not left:
            break
    for i, _ in dropped:
        state.quality.pop(i, None)
        shutil.rmtree(files.fem / f"inc-{i:04d}", ignore_errors=True)
        (files.vtu / f"inc-{i:04d}.vtu").unlink(missing_ok=True)
    summary.truncate_history(files.root, keep)
    if scene.output.vtu and state.accepted:
        vtu.write_pvd(files.root / "results.pvd", [(lf, f"vtu/inc-{i:04d}.vtu") for i, lf in state.accepted])
    return dropped
