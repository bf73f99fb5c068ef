"""Orthogonal cutting, finite-element part (issue 17 prototype): a chip forms at the rounded edge.

The steel scene (adiabatic Johnson-Cook), cut 60 um (0.4 h) in 12 increments on its 25 um mesh, remeshed
every 2 increments: the material in front of the rake face must rise above the top of the uncut layer (a
chip starting up the rake face), the forces on the tool must be positive and finite with F_c > F_t, the
plastic work must heat the primary zone, and the remeshes must carry the updated-Lagrangian state (the
re-equilibration converges from the transferred state)."""

import csv
import json
import math

import numpy as np
import pytest

from wendel.cutting.fe import fe_scene, tool_at_start
from wendel.cutting.fe_frames import rounded_outline
from wendel.cutting.fe_run import run_cut
from wendel.scene import load
from wendel.scene.reading import SceneError

from conftest import WORKFLOWS

STEEL = WORKFLOWS / "cutting-aisi1045.toml"


def test_tool_starts_in_front_of_the_step_with_its_tip_on_the_machined_level():
    scene = load(STEEL)
    c = scene.cutting
    t = tool_at_start(c, 0.9)
    corners = rounded_outline(t["vertices"], t["radii"], per_arc=200)
    w = np.linspace(0, 1, 2000)[:, None]          # the straight faces sampled too
    outline = np.concatenate([a + w * (b - a) for a, b in zip(corners, np.roll(corners, -1, axis=0))])
    h = c.uncut_thickness * 1e3
    assert outline[:, 1].min() == pytest.approx(0.0, abs=1e-6)            # the tip on y = 0 (200 arc points)
    assert np.array(t["tip"]) == pytest.approx([outline[np.argmin(outline[:, 1]), 0], 0.0], abs=1e-4)
    layer = outline[(outline[:, 1] >= 0) & (outline[:, 1] <= h)]
    assert layer[:, 0].min() == pytest.approx(0.9 + 0.02 * h, abs=1e-4)   # 3 um in front of the step face
    edge = corners[np.argmin(corners[:, 1]) + np.arange(-3, 4)]
    centre = np.array(t["tip"]) + [0.0, c.edge_radius * 1e3]
    assert np.linalg.norm(edge - centre, axis=1) == pytest.approx(c.edge_radius * 1e3, rel=1e-6)
    fe = fe_scene(scene)
    assert fe.kinematics.updated_lagrangian and fe.contact.path.x[-1] == pytest.approx(-c.cut_length * 1e3)
    assert fe.material.E == pytest.approx(scene.material.E * 1e-6)


def test_fe_cut_forms_a_chip(tmp_path, capsys):
    scene = load(STEEL, smoke=True)
    scene.geometry.model_extra["length"] = 1.2e-3     # m: a shorter block than the scene's (the cut is 60 um)
    scene.cutting.cut_length = 0.06e-3        # m: 12 increments of 5 um, as in the full scene
    scene.loading.steps = 12
    scene.cutting.remesh_every = 2
    root = run_cut(scene, STEEL, tmp_path / "cut", smoke=False, progress=lambda *_: None, frames=True)
    rows = list(csv.DictReader((root / "cutting.csv").open()))
    assert len(rows) >= 12
    last = {k: float(v) for k, v in rows[-1].items()}
    h = scene.cutting.uncut_thickness
    assert last["tool_travel_m"] == pytest.approx(0.06e-3, rel=1e-9)
    fc = np.array([float(r["Fc_N"]) for r in rows])
    ft = np.array([float(r["Ft_N"]) for r in rows])
    assert np.all(np.isfinite(fc)) and np.all(np.isfinite(ft)) and np.all(fc > 0) and np.all(ft > 0)
    assert np.all(fc > ft)
    # a chip: material rises above the uncut layer's top along the rake face (elastic compression: < 1 um)
    assert last["chip_rise_m"] > 0.05 * h
    assert last["contact_length_m"] > 0.5 * h
    assert last["max_plastic_strain"] > 0.3
    assert last["max_temperature_K"] > scene.thermal.T_ref + 50           # adiabatic heating
    s = json.loads((root / "summary.json").read_text())
    assert len(s["remeshes"]) >= 5
    # the scalar return mapping takes the chord's root when a Newton step leaves its bracket (plasticity.idp;
    # measured 20 at most here, and 219 Newton iterations in 17 increments; with the midpoint the smoke run's
    # increments took 50-75)
    hist = list(csv.DictReader((root / "history.csv").open()))
    assert max(int(x["plast_local_iterations"]) for x in hist) <= 30
    for k in range(1, 4):
        r = json.loads((root / "remesh" / f"remesh-{k}.json").read_text())
        assert r["residual_after_reequilibration"] < 1e-6 and r["inverted_before"] == 0
        assert r["integral_p_after"] == pytest.approx(r["integral_p_before"], rel=0.1)
        # the staged re-equilibration: each of the 4 stages but the last hands on to the next once its relative
        # residual is below remesh.relax_tol (the cut's 1e-2), the next releasing its share of the out-of-balance:
        # 3 hand-ons; the last converges (above)
        assert r["relax_handovers"] == r.get("relax_steps", 4) - 1 and 0 < r["relax_handover_residual"] < 1e-2
    assert (root / "frames" / f"inc-{int(rows[-1]['increment']):04d}.png").stat().st_size > 10000
    summary = json.loads((root / "cutting.json").read_text())
    assert summary["oxley"]["Fc_N"] > 0
    # the steady-state report: 60 um is 0.4 h, shorter than its window (1 h): no steady state, but the means
    # of the whole remesh cycles (2 increments each) are there, at increasing travel
    st = summary["steady"]
    assert st["raw"] is None and st["cycles"] is None and st["length_m"] == pytest.approx(h)
    travel = [c["tool_travel_m"] for c in st["cycle_means"]]
    assert len(travel) >= 4 and all(c["increments"] >= 2 for c in st["cycle_means"]) and np.all(np.diff(travel) > 0)
    assert (root / "chip.gif").stat().st_size > 10000
    # its Newton steps by whether they changed the contact or friction sets (wendel.cutting.fe_newton): every
    # accepted increment's iterations counted, as summary.json counts them
    from wendel.cutting.fe_newton import newton_sets
    ns = newton_sets(root)
    assert ns["increments"] == s["increments"] and ns["iterations"] == s["newton_iterations"]
    assert ns["failed_tries"] == len(list((root / "failed-attempts").glob("*-newton.csv")))
    assert 0 < ns["steps_counted"] <= ns["iterations"] + ns["failed_iterations"]
    assert 0 <= ns["set_change_share"] <= 1 and ns["contraction_without"] < 1
    # the bench's row of this run folder (python -m wendel.bench.cutting RUN MATERIAL): the last h's means
    from wendel.bench.cutting import main as bench_row
    from wendel.cutting.fe_steady import window
    assert bench_row([str(root), "steel"]) == 0
    said = dict(line.split(" ", 1) for line in capsys.readouterr().out.splitlines())
    w = window([{k: float(v) for k, v in r.items()} for r in rows], h)
    assert float(said["last_h_Fc_N"]) == pytest.approx(w["steady_Fc_N"], rel=1e-5) and said["mu"] == "0.5"
    assert int(said["failed_tries"]) == ns["failed_tries"] and said["steady"] == "False"
    assert bench_row([str(tmp_path), "steel"]) == 2
    assert capsys.readouterr().err == f"{tmp_path}: not the run folder of a cutting scene\n"
    assert bench_row([str(root), "brass"]) == 2
    assert capsys.readouterr().err == "usage: python -m wendel.bench.cutting RUN steel|titanium\n"


def test_fe_cut_compiled_residual_pass_is_the_freefem_one(tmp_path):
    # friction.idp's pass over the contact nodes at each residual on the cut (the rounded polygon tool moving
    # along its path, the current masses of the updated-Lagrangian surface, Coulomb with the shear cap),
    # compiled against the FreeFEM language's loop: friction_residual = "check" runs both at every residual
    # (line searches included) and records their largest relative difference: exactly 0 (the same arithmetic in
    # the same order), also after a remesh.
    scene = load(STEEL, smoke=True)
    scene.cutting.friction_residual = "check"
    scene.cutting.remesh_every = 2
    root = run_cut(scene, STEEL, tmp_path / "cut", smoke=True, progress=lambda *_: None, frames=False)
    recs = [json.loads((d / "record.json").read_text()) for d in sorted((root / "fem").glob("inc-*"))
            if (d / "done").is_file()]
    assert len(recs) >= 4 and max(r["friction_slip_nodes"] for r in recs) > 0
    assert all(r["friction_residual_diff"] == 0.0 for r in recs), [r["friction_residual_diff"] for r in recs]


def test_fe_cut_fbar_compiled_patch_term_is_the_freefem_one(tmp_path):
    # F-bar on the cut (contact rows: the patch term is added to K, not solved as the augmented system):
    # kinematics-fbar.idp adds Dfree Y' Ds Z to K in one compiled pass (wendelFbarAdd); the same launch with
    # -ul_fbar_product 1 (FreeFEM's sparse products and sum) takes the same Newton path to round-off.
    from wendel import freefem
    scene = load(STEEL, smoke=True)
    scene.cutting.volumetric = "fbar"
    root = run_cut(scene, STEEL, tmp_path / "cut", smoke=True, progress=lambda *_: None, frames=False)
    words = (root / "freefem.log").read_text().splitlines()[0].split()
    assert "-ul_volumetric" in words and words[words.index("-ul_volumetric") + 1] == "1"
    opts = words[words.index("-out") + 2:]
    out = tmp_path / "lang"
    freefem.run("mechanics.edp", opts + ["-ul_fbar_product", "1"], out)
    incs = sorted(d.name for d in out.glob("inc-*") if (d / "done").is_file())
    assert len(incs) >= 2
    for inc in incs:
        a = [float(r["residual"]) for r in csv.DictReader((root / "fem" / inc / "newton.csv").open())]
        b = [float(r["residual"]) for r in csv.DictReader((out / inc / "newton.csv").open())]
        assert len(a) == len(b) >= 2 and max(abs(x - y) for x, y in zip(a, b)) < 1e-9 * max(a), (inc, a, b)


def test_fe_cut_fbar_takes_shares_of_the_step_first_on_a_new_mesh(tmp_path):
    # Remeshed after 2 of its 4 steps: F-bar's first steps on the new mesh are 1/4 and 1/2 of the step
    # (cutting.first_step; README "The remesh's own cost"), then the whole ones; its re-equilibration's stages
    # hand on below cutting.relax_tol
    scene = load(STEEL, smoke=True)
    scene.cutting.volumetric = "fbar"
    scene.cutting.remesh_every = 2
    root = run_cut(scene, STEEL, tmp_path / "cut", smoke=True, progress=lambda *_: None, frames=False)
    hist = list(csv.DictReader((root / "history.csv").open()))
    lfs = [float(r["load_factor"]) for r in hist]
    reeq = [k for k, r in enumerate(hist) if r["reequilibration"] == "1"]
    assert reeq and lfs[reeq[0]] == pytest.approx(0.5) and lfs[reeq[0] + 1] <= 0.5625 + 1e-12, lfs
    assert all(any(abs(x - lf) < 1e-12 for x in lfs) for lf in (0.5625, 0.625, 0.75, 1.0)), lfs
    rep = json.loads((root / "remesh" / "remesh-1.json").read_text())
    assert rep["first_steps"] == pytest.approx([0.5625, 0.625]) and rep["relax_handover_residual"] < 1e-2


@pytest.mark.parametrize("volumetric, heat, words", [
    ("fbar", "adiabatic", ['thermal.coupling = "staggered"', "r/3 to r/5", 'volumetric = "cell"']),
    ("fbar", "staggered", ["another edge size (cutting.edge_size)", "r/4 stopped at 421 um", 'volumetric = "cell"']),
    ("fbar", "none", ["cutting.edge_size r/2 or more", 'volumetric = "cell"']),
    ("cell", "adiabatic", [])])
def test_an_fbar_cut_that_tangles_stops_with_what_to_change(tmp_path, volumetric, heat, words):
    # The last step cut of a failing increment stops the run; when F-bar tangled the mesh the message says which
    # keys go on (README "What inverts the fine F-bar meshes"): heated adiabatically, conduction first; with
    # conduction another edge size; without heat coarser ones; with the cells' own volume change nothing more.
    from wendel import freefem
    from wendel.errors import StepCutError
    from wendel.loop.checkpoint import RunFiles, State
    from wendel.loop.steps import cut_step
    scene = load(STEEL, smoke=True)
    scene.cutting.volumetric = volumetric
    if heat == "none":
        scene.thermal.beta = 0.0
    else:
        scene.thermal.coupling = heat
    scene = fe_scene(scene)
    scene.remesh.on_failure = False     # stop here (remeshed and tried again: tests/test_remesh_failure.py)
    lf = 0.5 + scene.loading.nominal_step() / 2 ** (scene.loading.max_cuts + 1)      # no halving left
    state = State(accepted=[(7, 0.5)], pending=[lf])
    failure = freefem.NewtonFailure({"increment": 8, "load_factor": lf, "reason": "mesh would invert"})
    with pytest.raises(StepCutError) as err:
        cut_step(scene, RunFiles(tmp_path), state, failure, lambda *_: None)
    text = str(err.value)
    assert "mesh would invert, even after" in text and "1 accepted increments are kept" in text
    assert all(w in text for w in words), text
    assert ("F-bar (kinematics.volumetric" in text) == (volumetric == "fbar")


def test_the_cut_takes_the_scenes_newton_tolerance_and_1e_8_without_one(tmp_path):
    """numerics.newton_tol reaches the FE cut where the scene sets it (it was read and then overridden by the
    cut's own 1e-8 until session 23); without it the cut keeps 1e-8, not the general scenes' 1e-9."""
    assert fe_scene(load(STEEL)).numerics.newton_tol == 1e-8
    text = STEEL.read_text()
    assert "[numerics]" not in text
    scene = tmp_path / "loose.toml"
    scene.write_text(text + "\n[numerics]\nnewton_tol = 1.0e-6      # 1\n")
    assert fe_scene(load(scene)).numerics.newton_tol == 1e-6
    scene.write_text(text + "\n[numerics]\nnewton_maxit = 50\n")     # read and not used: refused, by file and key
    with pytest.raises(SceneError, match=r"loose\.toml.*numerics\.newton_maxit.*only numerics\.direct, newton_tol"):
        load(scene)


def test_a_resumed_report_reads_the_cutting_scene_as_run(tmp_path):
    """A cut whose scene a bench or a script changed in memory (here the block's length) is reported after a
    resume from the scene as run (cutting-scene.json), not from the file's: the same cutting.csv. Session 23: a
    resumed r/4 bench cut was reported with the file's block and edge, its chip thickness NaN throughout."""
    from wendel.cutting.fe_run import SCENE_JSON, report_resumed
    cut = load(STEEL, smoke=True)
    assert cut.geometry.model_extra["length"] != 1.2e-3
    cut.geometry.model_extra["length"] = 1.2e-3
    root = run_cut(cut, STEEL, tmp_path / "cut", smoke=True, progress=lambda *_: None, frames=False)
    assert json.loads((root / SCENE_JSON).read_text())["geometry"]["length"] == 1.2e-3
    before = (root / "cutting.csv").read_text()
    (root / "cutting.csv").unlink()
    report_resumed(root, progress=lambda *_: None)
    assert (root / "cutting.csv").read_text() == before


@pytest.mark.parametrize("measure, span", [("cycles", 30e-6), ("filtered", 20e-6)])
def test_a_cut_that_asks_ends_at_its_steady_state_and_says_where(tmp_path, measure, span):
    """cutting.stop_when_steady: the loop asks wendel.cutting.fe_stop after each launch (a remesh cycle); the cut
    ends at the end of the first cycle where the cycle means of F_c, F_t and chip thickness have stayed within
    cutting.steady_tol over cutting.steady_length (loose here: 20 % over 30 um, found at about 110 um of the 200),
    or with steady_measure = "filtered" their running means over 20 um within 20 % over 40 um (about 110 um too)."""
    from wendel.cutting.fe_run import resumed_rule
    from wendel.cutting.fe_steady import steady
    from wendel.loop.checkpoint import load_state
    from wendel.loop.quasistatic import run
    scene = load(STEEL, smoke=True)
    scene.geometry.model_extra["length"] = 1.4e-3
    scene.cutting.cut_length, scene.loading.steps, scene.cutting.remesh_every = 0.2e-3, 40, 4
    scene.cutting.stop_when_steady, scene.cutting.steady_tol, scene.cutting.steady_length = True, 0.2, span
    scene.cutting.steady_measure = measure
    said = []
    root = run_cut(scene, STEEL, tmp_path / "cut", smoke=False, progress=said.append, frames=False)
    rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader((root / "cutting.csv").open())]
    cut = json.loads((root / "cutting.json").read_text())
    stop, summary = cut["stopped_at_steady"], json.loads((root / "summary.json").read_text())
    assert rows[-1]["tool_travel_m"] < 0.19e-3 and stop["increments_left"] > 0     # ended before the cut's length
    assert summary["completed"] and summary["pending_increments"] == 0 and summary["increments"] == len(rows)
    assert stop["increment"] == rows[-1]["increment"]
    assert summary["outputs"]["stopped_at_steady_m"] == stop["tool_travel_m"]
    assert stop["tool_travel_m"] == pytest.approx(rows[-1]["tool_travel_m"])
    # the report's steady state (the same tolerance and length) is the window the loop stopped on ...
    assert cut["steady"][measure] == stop["window"] and cut["steady"]["tol"] == 0.2 and stop["measure"] == measure
    assert stop["window"]["end_m"] - stop["window"]["start_m"] >= span * (1 + (measure == "filtered")) * (1 - 1e-9)
    assert max(stop["window"]["spreads"].values()) <= 0.2 and stop["check_seconds"] > 0
    # ... and it was not there one launch earlier: the rows before the last remesh cycle have no window
    last_reeq = max(k for k in range(1, len(rows)) if rows[k]["tool_travel_m"] == rows[k - 1]["tool_travel_m"])
    assert steady(rows[:last_reeq], span, 0.2)[measure] is None
    assert any("cutting.stop_when_steady" in s for s in said)
    # resumed: nothing left to cut; the resumed loop gets the same rule, which finds the same window at once
    history = (root / "history.csv").read_text()
    assert run(None, resume=root, progress=lambda *_: None) == root
    assert (root / "history.csv").read_text() == history
    assert "stopped_at_steady" in json.loads((root / "cutting.json").read_text())
    rule = resumed_rule(root, progress=lambda *_: None)
    assert rule is not None and rule(load_state(root)[2]) is True
    scene.cutting.stop_when_steady = False
    (root / "cutting-scene.json").write_text(scene.model_dump_json())
    assert resumed_rule(root) is None
