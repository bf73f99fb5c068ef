"""The FE cut's Newton method on the states it meets: its tangent against finite differences of its residual away
from the contact nodes (edp/lib/fdcheck.idp, which holds them: there the residual holds the gap, stick and slip
rows), and the replay of a cut's last launch with other Newton options (`python -m wendel.bench.newton_replay`)."""

from __future__ import annotations

import csv
import json
import statistics
import tempfile
from pathlib import Path

import pytest

from conftest import WORKFLOWS
from wendel.bench import newton_replay
from wendel.bench.profile import last_launch


@pytest.fixture(scope="module")
def cut(tmp_path_factory) -> Path:
    """The smoke-size steel cut with the steady scenes' F-bar and conduction, remeshed every 2 increments."""
    from wendel.cutting.fe_run import run_cut
    from wendel.scene import load
    path = WORKFLOWS / "cutting-aisi1045.toml"
    scene = load(path, smoke=True)
    scene.cutting.volumetric = "fbar"
    scene.thermal.coupling = "staggered"
    scene.cutting.remesh_every = 2
    return run_cut(scene, path, tmp_path_factory.mktemp("cut") / "run", smoke=True, progress=lambda *_: None,
                   frames=False)


def test_the_cut_tangent_is_its_residual_derivative_away_from_the_contact_nodes(cut):
    # the last launch again with -newton_fd_check: K d against the residual's central differences in random
    # directions (the contact nodes held, their rows left out) and along the Newton steps (whose set changes make
    # the residual's kinks). Measured (session 31): 2.7e-9 median, 2.3e-5 at most over 33 directions; with the contact
    # nodes moved and their rows compared, 3.1 % median (the check before session 31); on the end of the steady
    # steel cut, 5.3e-5 median (fdcheck.idp)
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "fd"
        assert newton_replay.replay(last_launch(cut), ["-newton_fd_check", "1e-6"], keep=out)["exit"] == 0
        rows = list(csv.DictReader((out / "fdcheck.csv").open()))
    random = [float(r["relative_difference"]) for r in rows if r["direction"] == "random" and r["iteration"] != "0"]
    assert len(random) >= 5
    assert statistics.median(random) < 1e-6, random


def test_a_replay_of_the_last_launch_takes_its_increments_and_iterations(cut):
    # the replay as it ran accepts what the launch accepted with the same Newton iterations; an option changes it
    words = last_launch(cut)
    plain = newton_replay.replay(words, [])
    launch = [p for p in sorted((cut / "fem").glob("inc-*")) if (p / "done").is_file()]
    assert plain["exit"] == 0 and plain["increments"] >= 1
    ran = [sum(1 for _ in csv.DictReader((p / "newton.csv").open())) - 1 for p in launch][-plain["increments"]:]
    assert plain["iterations"] == sum(ran)
    for opts, said in ((["-newton_ls_memory", "0"], "mechanics.idp: -newton_ls_memory must be >= 1, got 0"),
                       (["-therm_omega", "1.5"], "thermal.idp: -therm_omega must be in (0, 1], got 1.5")):
        with tempfile.TemporaryDirectory() as tmp:
            bad = newton_replay.replay(words, opts, keep=Path(tmp) / "bad")
            assert bad["exit"] == 3 and bad["increments"] == 0
            assert said in (Path(tmp) / "bad" / "error.txt").read_text()


def test_newton_rows_count_the_points_in_flow_and_their_switches(cut):
    # plasticity's newton.csv columns (plastic_points, plastic_switches: the points that changed between flow and
    # elastic since the last row) stand before the contact's, every row as long as the header; the switches are a
    # symmetric difference of two sets: | |A| - |B| | <= |A xor B| <= |A| + |B|
    rows = list(csv.reader((cut / "newton.csv").open()))
    head = rows[0]
    assert head.index("plastic_points") + 1 == head.index("plastic_switches") < head.index("contact_active")
    assert all(len(r) == len(head) for r in rows[1:])
    i, j = head.index("plastic_points"), head.index("plastic_switches")
    points = [(int(r0[i]), int(r[i]), int(r[j])) for r0, r in zip(rows[1:], rows[2:]) if r0[:2] == r[:2]]
    assert len(points) > 10 and max(s for _, _, s in points) > 0     # consecutive rows of one increment
    for a, b, s in points:
        assert abs(a - b) <= s <= a + b, (a, b, s)


def test_a_step_from_an_accepted_state_is_the_step_the_run_made(cut):
    # python -m wendel.bench.newton_replay --states: a whole step from an accepted state with the first guess the
    # loop gives it converges in the run's own Newton iterations; without that guess it takes others (the launch
    # as it ran, the state and its tables: what the states experiment of session 31 stands on)
    hist = {int(r["increment"]): r for r in csv.DictReader((cut / "history.csv").open())}
    words = last_launch(cut)
    picked = [st for st in newton_replay.states(cut, 1, start=0.0) if st[0] + 1 in hist]
    assert picked, json.loads((cut / "checkpoint.json").read_text())["accepted"]
    n = picked[0][0]
    with tempfile.TemporaryDirectory() as tmp:
        full = newton_replay.step_from(cut, words, picked[0], "full", Path(tmp) / "full")
        bare = newton_replay.step_from(cut, words, picked[0], "nopred", Path(tmp) / "nopred")
    assert full["exit"] == 0 and full["increments"] == 1
    assert full["iterations"] == int(hist[n + 1]["newton_iterations"])
    assert bare["iterations"] + bare["failed_iterations"] != full["iterations"]
