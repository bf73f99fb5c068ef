"""What the loop does when a step or a re-equilibration fails for good on a remeshed run (``wendel.loop.steps``).

A re-equilibration after a scheduled remesh that fails in the most stages on every gmsh mesh drops the remesh and
goes on with the old mesh (when no cell of it is inverted); a forward step that fails even in its smallest cut is
remeshed and tried again (``remesh.on_failure``; when the first step on that mesh fails so too, once more
without the motion carried over the remesh, then the body is meshed again with another gmsh algorithm); F-bar
re-equilibrates once with the cells' own volume change before it gives a remesh up; what cannot go on stops with
a message that says what failed and keeps the accepted increments. The decisions are made on the loop's state,
without FreeFEM (the remesh of a forward failure is a real one in
``test_a_step_that_fails_for_good_is_remeshed_and_a_failing_first_step_meshed_again``)."""

import csv
import json

import pytest

from wendel import freefem
from wendel.cutting.fe import fe_scene
from wendel.errors import StepCutError
from wendel.loop import predictor
from wendel.loop.checkpoint import RunFiles, State
from wendel.loop.steps import RELAX_MAX, cut_step
from wendel.remesh.again import AGAIN
from wendel.remesh.batch import first_steps
from wendel.scene import load

from conftest import WORKFLOWS


def _reequilibrating(after_failed_step: bool, inverted: int, quality: float = 0.11, volumetric: str = "cell",
                     first: list | None = None):
    cut = load(WORKFLOWS / "cutting-aisi1045.toml", smoke=True)
    cut.cutting.volumetric = volumetric
    scene = fe_scene(cut)
    rep = {"remesh": 2, "after_increment": 9, "relax_steps": RELAX_MAX, "algorithm_2d_tries": len(AGAIN),
           "dimension": 2, "min_quality_before": quality, "inverted_before": inverted,
           "after_failed_step": after_failed_step, "first_steps": first or []}
    state = State(accepted=[(9, 0.5)], pending=[0.5] + (first or []) + [0.55, 0.6], remeshes=[rep],
                  reequilibrate=True)
    state.segments.append({"first": 10, "mesh": "meshes/mesh-2.msh", "ubase": None, "eps0": None,
                           "state": "remesh/state-2"})
    failure = freefem.NewtonFailure({"increment": 10, "load_factor": 0.5, "reason": "mesh would invert"})
    return scene, state, failure


def test_a_scheduled_remesh_that_cannot_be_reequilibrated_is_dropped_and_the_old_mesh_goes_on(tmp_path):
    scene, state, failure = _reequilibrating(False, 0)
    said = []
    cut_step(scene, RunFiles(tmp_path), state, failure, said.append)
    assert not state.reequilibrate and state.remeshes == [] and len(state.segments) == 1
    assert state.pending == [0.55, 0.6] and state.last == (9, 0.5)
    kept = json.loads((tmp_path / "failed-attempts" / "remesh-2-after-9.json").read_text())
    assert kept["algorithm_2d_tries"] == len(AGAIN)
    assert "going on with the mesh before it (min quality 0.11)" in said[-1]


def test_the_first_steps_on_a_new_mesh_are_a_share_of_the_step_and_leave_with_a_dropped_remesh(tmp_path):
    # the F-bar cut's remeshes put 1/4 and 1/2 of the next step before it (remesh.first_step = 0.25), and its
    # schedule of remeshes counts them (every 8 steps: after increments 8, 8 + 11, ...), the P1 cut's not (its
    # whole steps go); a remesh dropped takes them out
    cut = load(WORKFLOWS / "cutting-aisi1045.toml")
    cut.cutting.remesh_every = 8
    scene = fe_scene(cut)
    assert scene.remesh.first_step == 1 and scene.remesh.at[:3] == [8, 17, 26]
    assert first_steps(scene, 0.5, [0.55, 0.6]) == []
    cut.cutting.volumetric = "fbar"
    scene = fe_scene(cut)
    assert scene.remesh.first_step == 0.25 and scene.remesh.at[:3] == [8, 19, 30]
    assert first_steps(scene, 0.5, [0.55, 0.6]) == pytest.approx([0.5125, 0.525])
    scene.loading.adaptive = True           # adaptive loading plans its own steps
    assert first_steps(scene, 0.5, [0.55, 0.6]) == []
    scene, state, failure = _reequilibrating(False, 0, first=[0.5125, 0.525])
    cut_step(scene, RunFiles(tmp_path), state, failure, lambda *_: None)
    assert not state.reequilibrate and state.pending == [0.55, 0.6]


def test_fbar_reequilibrates_once_with_the_cells_own_volume_change_before_it_drops_the_remesh(tmp_path):
    # F-bar's re-equilibration failed in the most stages on every mesh: that increment once more with the cells'
    # own volume change (F-bar from the next; quasistatic.solve swaps -ul_volumetric for that launch only), at the
    # scene's stages; when that fails too, the remesh is dropped as without F-bar
    scene, state, failure = _reequilibrating(False, 0, volumetric="fbar")
    said = []
    cut_step(scene, RunFiles(tmp_path), state, failure, said.append)
    rep = state.remeshes[-1]
    assert rep["relax_cell"] is True and rep["relax_steps"] == scene.remesh.relax_steps and state.reequilibrate
    assert state.pending == [0.5, 0.55, 0.6] and "cells' own volume change" in said[-1]
    rep["relax_steps"] = RELAX_MAX
    cut_step(scene, RunFiles(tmp_path), state, failure, said.append)
    assert not state.reequilibrate and state.remeshes == [] and "going on with the mesh before it" in said[-1]


@pytest.mark.parametrize("after_failed_step, inverted, quality", [(True, 0, 0.11), (False, 3, 0.11), (False, 0, 0.049)])
def test_a_reequilibration_that_fails_for_good_stops_and_says_so(tmp_path, after_failed_step, inverted, quality):
    # made because a step failed (no second chance), the old mesh has inverted cells or is below half of
    # remesh.min_quality (0.1): stop, say what failed
    scene, state, failure = _reequilibrating(after_failed_step, inverted, quality)
    with pytest.raises(StepCutError) as err:
        cut_step(scene, RunFiles(tmp_path), state, failure, lambda *_: None)
    text = str(err.value)
    assert f"mesh would invert in the re-equilibration after remesh 2, even in {RELAX_MAX} stages on 3 meshes" in text
    assert "1 accepted increments are kept" in text
    assert json.loads((tmp_path / "stopped.json").read_text())["increment"] == 10


@pytest.mark.parametrize("on_failure, first", [(False, 1), (True, 9)])
def test_a_step_that_fails_for_good_stops_without_a_remesh_when_it_may_not(tmp_path, on_failure, first):
    # remesh.on_failure = false, or the last converged increment is the first on its mesh (remeshed already)
    scene = fe_scene(load(WORKFLOWS / "cutting-aisi1045.toml", smoke=True))
    scene.remesh.on_failure = on_failure
    lf = 0.5 + scene.loading.nominal_step() / 2 ** (scene.loading.max_cuts + 1)
    state = State(accepted=[(9, 0.5)], pending=[lf, 0.75])
    state.segments[0]["first"] = first
    failure = freefem.NewtonFailure({"increment": 10, "load_factor": lf, "reason": "mesh would invert"})
    with pytest.raises(StepCutError) as err:
        cut_step(scene, RunFiles(tmp_path), state, failure, lambda *_: None)
    assert "even after" in str(err.value) and state.remeshes == []


def test_a_step_that_fails_for_good_is_remeshed_and_a_failing_first_step_meshed_again(tmp_path):
    # A real cut (the steel scene's smoke with F-bar, 4 increments of 5 um) whose next step is made to fail in its
    # smallest cut: the last converged increment is remeshed (gmsh, transfer), the run re-equilibrates on the new mesh
    # (resumed, as the loop goes on after the remesh) and ends there; a second failure on that mesh stops it.
    from wendel.cutting.fe_run import run_cut
    from wendel.loop.checkpoint import load_state, save
    from wendel.loop.quasistatic import run
    steel = WORKFLOWS / "cutting-aisi1045.toml"
    cut = load(steel, smoke=True)
    cut.cutting.volumetric = "fbar"
    root = run_cut(cut, steel, tmp_path / "cut", smoke=True, progress=lambda *_: None, frames=False)
    files, scene, state, dimension = load_state(root)
    last, lf_last = state.last
    assert state.pending == [] and scene.remesh.on_failure
    lf = lf_last + scene.loading.nominal_step() / 2 ** (scene.loading.max_cuts + 1)
    state.pending = [lf]
    said = []
    cut_step(scene, files, state, freefem.NewtonFailure({"increment": last + 1, "load_factor": lf,
                                                         "reason": "mesh would invert"}), said.append, dimension)
    rep = state.remeshes[-1]
    assert rep["after_failed_step"] and rep["after_increment"] == last and state.reequilibrate
    assert state.pending == [lf_last] and (root / state.segments[-1]["mesh"]).is_file()
    assert any("remeshing increment" in s and "remesh.on_failure" in s for s in said)
    rep["relax_cell"] = True        # as after F-bar's failed re-equilibrations: with the cells' own volume change
    save(files, scene, state, dimension)
    run("", resume=root, progress=lambda *_: None)
    words = [ln for ln in (root / "freefem.log").read_text().splitlines() if ln.startswith("$ ")][-1].split()
    assert words[words.index("-ul_volumetric") + 1] == "0" and scene.kinematics.volumetric == "fbar"
    files, scene, state, dimension = load_state(root)
    assert state.last == (last + 1, lf_last) and not state.reequilibrate
    rows = list(csv.DictReader((root / "history.csv").open()))
    assert rows[-1]["increment"] == str(last + 1) and rows[-1]["reequilibration"] == "1"
    # the first step on that mesh fails in its smallest cut too: once more without the motion carried over the
    # remesh as its first guess, then the mesh is given up with its re-equilibration (the increment's files and
    # history rows go) and the same body meshed again with the next gmsh algorithm
    launches = sum(launch["increments"] for launch in state.launches)
    state.pending = [lf]
    failure = freefem.NewtonFailure({"increment": last + 2, "load_factor": lf, "reason": "mesh would invert"})
    assert "-predictor_du" in predictor.options(scene, files, state, dimension)
    cut_step(scene, files, state, failure, said.append, dimension)
    assert state.remeshes[-1]["first_guess_carried"] is False and state.pending == [lf]
    assert predictor.options(scene, files, state, dimension) == [] and "no motion carried over" in said[-1]
    cut_step(scene, files, state, failure, said.append, dimension)
    rep = state.remeshes[-1]
    assert len(state.remeshes) == 1 and rep["algorithm_2d_tries"] == 1 and rep["after_increment"] == last
    assert state.reequilibrate and state.last == (last, lf_last) and state.pending == [lf_last]
    assert sum(launch["increments"] for launch in state.launches) == launches - 1
    assert not (root / "fem" / f"inc-{last + 1:04d}").exists()
    assert list(csv.DictReader((root / "history.csv").open()))[-1]["increment"] == str(last)
    assert f"the first step on remesh 1's mesh: mesh would invert, even after" in said[-2]
    assert f"meshing again with gmsh algorithm {AGAIN[0]}" in said[-2]
    save(files, scene, state, dimension)
    run("", resume=root, progress=lambda *_: None)      # re-equilibrated on the body's other mesh
    files, scene, state, dimension = load_state(root)
    assert state.last == (last + 1, lf_last) and not state.reequilibrate
    state.remeshes[-1].update(algorithm_2d_tries=len(AGAIN), first_guess_carried=False)   # all tried: stop
    state.pending = [lf]
    with pytest.raises(StepCutError):
        cut_step(scene, files, state, failure, said.append, dimension)
    assert len(state.remeshes) == len(json.loads((root / "summary.json").read_text())["remeshes"])
