"""Step control of the quasi-static loop: adaptive load steps (plan, grow) and halving a step that failed."""

from __future__ import annotations

import json
import shutil

from .. import freefem
from ..errors import StepCutError
from ..scene.schema import Scene
from .checkpoint import RunFiles, State


def plan_step(scene: Scene, state: State) -> None:
    """Adaptive loading: put the next load factor (last + step, never past the next target) first."""
    loading = scene.loading
    if state.step is None:
        state.step = loading.nominal_step()
    target, last = state.pending[0], state.last[1]
    direction = 1.0 if target >= last else -1.0
    nxt = last + direction * state.step
    if (nxt - target) * direction < -1e-12 * max(1.0, abs(target)):
        state.pending.insert(0, nxt)


def grow_step(scene: Scene, state: State, files: RunFiles) -> None:
    """Adaptive loading: after an easy increment the step grows (up to loading.max_step)."""
    loading = scene.loading
    rec = json.loads((files.fem / f"inc-{state.last[0]:04d}" / "record.json").read_text())
    if rec["newton_iterations"] <= loading.easy_iterations:
        state.step = min(state.step * loading.grow, loading.max_step or loading.nominal_step())


RELAX_MAX = 64      # most stages of a re-equilibration (remesh.relax_steps doubled on failure)


def cut_step(scene: Scene, files: RunFiles, state: State, failure: freefem.NewtonFailure, progress,
             dimension: int = 2) -> None:
    """Halve the failed increment; when no cut is left, remesh and go on (``remesh.on_failure``, :func:`_remesh`)
    or stop with a clear message."""
    rec = failure.record
    inc = state.last[0] + 1
    failed = files.fem / f"inc-{inc:04d}"
    if failed.is_dir():
        keep = files.root / "failed-attempts"
        keep.mkdir(exist_ok=True)
        if (failed / "newton.csv").is_file():
            shutil.copyfile(failed / "newton.csv", keep / f"inc-{inc:04d}-lf-{rec['load_factor']:.6g}-newton.csv")
        shutil.rmtree(failed)
    reason = rec.get("reason", "Newton did not converge")
    lf_prev, lf_fail = state.last[1], state.pending[0]
    if state.reequilibrate and scene.remesh and lf_fail == lf_prev and state.remeshes:
        # the re-equilibration after a remesh (no step to cut): release the out-of-balance in twice the stages
        rep = state.remeshes[-1]
        stages = 2 * rep.get("relax_steps", scene.remesh.relax_steps)
        if stages <= RELAX_MAX:
            rep["relax_steps"] = stages
            state.cuts += 1
            progress(f"  increment {inc}: {reason} in the re-equilibration; again in {stages} stages")
            return
        from ..remesh.again import remesh_again
        if remesh_again(scene, files, state, progress):      # another mesh of the same body
            state.cuts += 1
            return
        if scene.kinematics.volumetric == "fbar" and not rep.get("relax_cell"):
            # F-bar's re-equilibration failed on every mesh: that increment alone with the cells' own volume change
            # (quasistatic.solve), F-bar again from the next. Session 19 (adiabatic, r/4): it went on a few
            # increments only; session 21 (conduction, r/2, stopped at 170 um): it cut through to 400 um
            rep["relax_cell"] = True
            rep["relax_steps"] = scene.remesh.relax_steps
            state.cuts += 1
            progress(f"  increment {inc}: {reason} in the re-equilibration; again with the cells' own volume change "
                     f"(F-bar from the next increment)")
            return
        if _keep_old_mesh(scene, files, state, progress, inc):
            state.cuts += 1
            return
    state.cuts += 1
    mid = lf_prev + 0.5 * (lf_fail - lf_prev)
    smallest = scene.loading.nominal_step() / 2 ** scene.loading.max_cuts
    if reason == "limit load reached" or abs(mid - lf_prev) < smallest * (1 - 1e-9):
        if reason != "limit load reached" and (_remesh(scene, files, state, dimension, progress, inc, reason)
                                               or _without_predictor(scene, files, state, dimension, progress,
                                                                     inc, reason)
                                               or _mesh_again(scene, files, state, progress, inc, reason)):
            return
        what = "limit load reached" if reason == "limit load reached" else \
            f"{reason}, even after {scene.loading.max_cuts} step halvings (loading.max_cuts)"
        if state.reequilibrate and state.remeshes and lf_fail == lf_prev:
            rep = state.remeshes[-1]
            what = (f"{reason} in the re-equilibration after remesh {rep.get('remesh')}, even in "
                    f"{rep.get('relax_steps')} stages on {rep.get('algorithm_2d_tries', 0) + 1} meshes of the body"
                    + (" and with the cells' own volume change" if rep.get("relax_cell") else ""))
        # the bracket of the limit (or of the failure): summary.json reports it
        (files.root / "stopped.json").write_text(json.dumps(
            {"increment": inc, "reason": what, "last_converged_load_factor": lf_prev,
             "first_failed_load_factor": lf_fail}, indent=1))
        raise StepCutError(
            f"increment {inc} (load factor {lf_prev:g} -> {lf_fail:g}): {what} between load factor {lf_prev:g} "
            f"(last converged) and {lf_fail:g} (first failed); "
            f"{len(state.accepted)} accepted increments are kept in {files.root}" + _hint(scene, reason))
    if scene.loading.adaptive:
        state.step = abs(mid - lf_prev)
        if not _target(scene, lf_fail):
            state.pending.pop(0)         # an intermediate point of the adaptive loading: plan_step re-plans
    state.pending.insert(0, mid)
    progress(f"  increment {inc}: {reason} at load factor {lf_fail:g}; cutting the step to {mid:g}")


def _target(scene: Scene, lf: float) -> bool:
    """Whether ``lf`` is one of the loading's target load factors (not a point a cut or the adaptive loading put in)."""
    return any(abs(lf - t) <= 1e-12 * max(1.0, abs(t)) for t in scene.loading.load_factors())


def _keep_old_mesh(scene: Scene, files: RunFiles, state: State, progress, inc: int) -> bool:
    """The re-equilibration after a remesh failed on every mesh: when the old mesh can go on (no cell inverted,
    its min SICN at least half of ``remesh.min_quality``; the remesh was not made because a step failed), drop the
    remesh and go on with the old mesh, remeshed again when its quality or the schedule next says. Measured on
    the FE cut (README, session 21): the F-bar cuts with conduction that stopped so had remeshed on schedule at a
    min SICN of 0.11-0.24."""
    from ..remesh.again import drop_last_remesh
    rep = state.remeshes[-1]
    if rep.get("after_failed_step") or rep.get("inverted_before", 1) > 0 \
            or rep.get("min_quality_before", 0.0) < 0.5 * scene.remesh.min_quality:
        return False
    drop_last_remesh(state)
    keep = files.root / "failed-attempts"
    keep.mkdir(exist_ok=True)
    (keep / f"remesh-{rep.get('remesh')}-after-{rep.get('after_increment')}.json").write_text(json.dumps(rep, indent=1))
    progress(f"  increment {inc}: the re-equilibration after remesh {rep.get('remesh')} failed on every mesh; "
             f"going on with the mesh before it (min quality {rep.get('min_quality_before', float('nan')):.3g})")
    return True


def _remesh(scene: Scene, files: RunFiles, state: State, dimension: int, progress, inc: int, reason: str) -> bool:
    """A forward step that failed even in its smallest cut: remesh the last converged increment and go on from
    it with the nominal steps (``remesh.on_failure``; once per mesh: not when that increment is the first on
    its mesh). Measured on the FE cut (README, session 21): the cells under the edge lose quality over the
    increments (min SICN 0.39 -> 0.11 in ten) and the step fails just before the 0.1 of ``remesh.min_quality``."""
    r = scene.remesh
    last = state.last[0]
    if not (r and r.on_failure and state.accepted and not state.reequilibrate
            and last > state.segments[-1]["first"] and len(state.remeshes) < r.max_remeshes):
        return False
    from ..remesh.step import maybe_remesh
    state.pending = [p for p in state.pending if _target(scene, p)]
    if scene.loading.adaptive:
        state.step = scene.loading.nominal_step()
    progress(f"  increment {inc}: {reason}, even after {scene.loading.max_cuts} step halvings: remeshing "
             f"increment {last} and going on (remesh.on_failure)")
    maybe_remesh(scene, files, state, dimension, progress, failed=True)
    return True


def _first_on_new_mesh(scene: Scene, state: State) -> bool:
    """Whether the last accepted increment is the re-equilibration of the last remesh (the step that failed is the
    first forward step on that mesh)."""
    return bool(scene.remesh and scene.remesh.on_failure and state.remeshes and not state.reequilibrate
                and len(state.segments) > 1 and state.last[0] == state.segments[-1]["first"])


def _without_predictor(scene: Scene, files: RunFiles, state: State, dimension: int, progress, inc: int,
                       reason: str) -> bool:
    """The first forward step on a new mesh failed even in its smallest cut with the first guess carried over the
    remesh (:mod:`wendel.loop.predictor`: the old mesh's last motion): once more from the re-equilibrated state
    itself. Measured (README, session 26): the 2.4 mm F-bar cut with conduction, stopped at 2,068 um with its first
    step failing so on three meshes of the body, went on at once from the re-equilibrated state."""
    from . import predictor
    if scene.numerics.predictor != "extrapolate" or not _first_on_new_mesh(scene, state):
        return False
    rep = state.remeshes[-1]
    if rep.get("first_guess_carried") is False or not predictor.options(scene, files, state, dimension):
        return False            # tried so already, or no motion was carried (the same try again)
    rep["first_guess_carried"] = False
    progress(f"  increment {inc}: {reason}, even after {scene.loading.max_cuts} step halvings, the first step on "
             f"remesh {rep.get('remesh')}'s mesh; again from the re-equilibrated state (no motion carried over)")
    return True


def _mesh_again(scene: Scene, files: RunFiles, state: State, progress, inc: int, reason: str) -> bool:
    """The first forward step on a new mesh failed even in its smallest cut, its re-equilibration converged: that
    mesh is given up with its re-equilibration and the same deformed body meshed again with the next gmsh 2D
    algorithm (:data:`wendel.remesh.again.AGAIN`, as after a re-equilibration that failed), and the loop goes on
    from the increment the remesh was made from. Measured (README, session 26): the 2.4 mm F-bar cut with
    conduction stopped at 1,551 um so, its first step on remesh 67 failing in every cut."""
    from ..remesh.again import can_mesh_again, remesh_again
    from ..remesh.batch import forget
    if not (_first_on_new_mesh(scene, state) and can_mesh_again(state.remeshes[-1])):
        return False
    rep = state.remeshes[-1]
    forget(scene, files, state, state.last[0] - 1)          # the re-equilibration on the mesh given up
    return remesh_again(scene, files, state, progress, f"the first step on remesh {rep.get('remesh')}'s mesh: "
                        f"{reason}, even after {scene.loading.max_cuts} step halvings",
                        pending=[lf for lf in state.pending if _target(scene, lf)])


def _hint(scene: Scene, reason: str) -> str:
    """What a user can change when F-bar tangles the mesh (measured on the FE cut, README "What inverts the fine
    F-bar meshes: adiabatic softening"): heated adiabatically, the Johnson-Cook flow softens with its own heat and
    localizes into the small cells at the edge, and the same cuts with conduction run through on edge meshes of
    r/3 to r/5, where r/2 stopped; without heat every edge mesh from r/2 to r/4 ran through."""
    if reason != "mesh would invert" or scene.kinematics.volumetric != "fbar":
        return ""
    th = getattr(scene, "thermal", None)
    text = ("; F-bar (kinematics.volumetric, in a cutting scene cutting.volumetric = \"fbar\") inverts cells "
            "where many small ones flow plastically")
    if th is not None and th.beta > 0 and th.coupling == "adiabatic":
        return text + (": heated adiabatically (thermal.coupling = \"adiabatic\"), the flow softens with its own "
                       "heat and localizes there; with heat conduction (thermal.coupling = \"staggered\") the edge "
                       "meshes r/3 to r/5 cut through in wendel bench cutting-mesh. Or volumetric = \"cell\" (P1 "
                       "locks: stiffer, but it goes on)")
    if th is not None and th.beta > 0:
        return text + (": with conduction the edge sizes r/2 to r/5 cut 400 um through (wendel bench cutting-mesh) "
                       "and r/2 and r/3 1.2 mm, where r/4 stopped at 421 um (session 23): another edge size "
                       "(cutting.edge_size), or volumetric = \"cell\" (P1 locks: stiffer, but it goes on)")
    return text + (": coarser cells there (at a cutting edge cutting.edge_size r/2 or more) or volumetric = "
                   "\"cell\" (P1 locks: stiffer, but it goes on)")
