"""The FE cut's Newton method on the states it meets: its tangent against finite differences of its residual away
from the contact nodes (edp/lib/fdcheck.idp, which holds them: there the residual holds the gap, stick and slip
rows), the replay of a cut's last launch with other Newton options (`python -m wendel.bench.newton_replay`), and
the end of a Newton iteration that cycles (edp/lib/newtoncycle.idp, mechanics.idp's -newton_cycle)."""

from __future__ import annotations

import csv
import json
import statistics
import subprocess
import tempfile
from pathlib import Path

import pytest

from conftest import WORKFLOWS
from wendel import freefem
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


# Relative residuals of Newton iterations of the steel cut (session 32, cutting-aisi1045-steady.toml, 3 digits): a
# failed try that settled into a cycle of period 4 and ran to the 100th iteration, and two accepted increments that
# wandered for 20 iterations before converging
CYCLING = [4.78, 0.345, 0.358, 0.4, 0.296, 0.189, 0.167, 0.122, 0.145, 0.0923, 0.0742, 0.0566, 0.0589, 0.0576,
           0.0682, 0.0526, 0.0703, 0.0551, 0.0679, 0.0528, 0.071, 0.0518, 0.0687, 0.053, 0.0669, 0.052, 0.0676,
           0.0526, 0.0659, 0.052, 0.067, 0.0528, 0.066, 0.0519, 0.067, 0.0528, 0.066, 0.0519, 0.067, 0.0528, 0.066]
WANDERING = [[3.9, 0.34, 0.51, 0.45, 0.37, 0.35, 0.57, 0.55, 0.48, 0.5, 0.42, 0.74, 0.61, 0.64, 0.58, 0.55, 0.51, 0.55,
              0.4, 0.3, 0.21, 0.15, 0.11, 0.074, 0.038, 0.0057, 0.0002, 4.9e-07],
             [1.5, 0.35, 0.53, 0.5, 0.47, 0.63, 0.73, 0.74, 0.63, 0.66, 0.68, 0.53, 0.42, 0.79, 0.42, 0.52, 0.42, 0.41,
              0.18, 0.12, 0.21, 0.2, 0.19, 0.11, 0.076, 0.0041, 0.0011, 9.2e-05, 4.2e-06]]


# an accepted increment that crept down by less than 1 % an iteration (16-19) and converged at iteration 45
CREEPING = [9.724, 0.5375, 0.6334, 0.7345, 0.7302, 0.6215, 0.7083, 0.7135, 0.5869, 0.5551, 0.4855, 0.4913, 0.4602,
            0.4474, 0.3639, 0.4034, 0.381, 0.3773, 0.3748, 0.3735, 0.3579, 0.3358, 0.3228, 0.3369]


def _cycle_at(sequences: list[list[float]], it0: int = 0) -> list[tuple[int, int]]:
    """(iteration, period) at which newtonCycleAt of edp/lib/newtoncycle.idp first finds a cycle in each sequence
    (P = 4, 1 %; -1 and 0 when it finds none), run by FreeFEM."""
    with tempfile.TemporaryDirectory() as tmp:
        seq = Path(tmp) / "seq.txt"
        seq.write_text(f"{len(sequences)}\n" + "".join(f"{len(s)} " + " ".join(map(repr, s)) + "\n" for s in sequences))
        script = Path(tmp) / "cycle.edp"
        script.write_text(f"""include "lib/newtoncycle.idp"
ifstream f("{seq}");
int m; f >> m;
for (int s = 0; s < m; ++s) {{
    int n; f >> n;
    real[int] h(n);
    for (int i = 0; i < n; ++i) f >> h[i];
    int at = -1, per = 0;
    for (int it = 0; it < n && at < 0; ++it) {{
        newtonCycleAt(h, it, {it0}, 4, 0.01, per)
        if (per > 0) at = it;
    }}
    cout << "cycle " << at << " " << per << endl;
}}
""")
        p = subprocess.run(["FreeFem++-mpi", "-nw", "-v", "0", str(script)], env=freefem.environment(),
                           capture_output=True, text=True, timeout=60)
    assert p.returncode == 0, p.stdout + p.stderr
    return [tuple(map(int, line.split()[1:])) for line in p.stdout.splitlines() if line.startswith("cycle ")]


def test_a_newton_cycle_is_found_and_a_wandering_newton_that_converges_is_not():
    # the cut's cycle of period 4 is found at iteration 40 (the 100-iteration try would have ended there), an exact
    # alternation at iteration 10 (the earliest); a constant residual (no oscillation), the creeping and the two
    # wandering increments that converged and a converging sequence never; iterations before the stage (it0) do not
    # count
    alternating = [1.0] + [0.5, 0.25] * 15
    converging = [10.0 ** -k for k in range(14)]
    assert _cycle_at([CYCLING, alternating, [0.3] * 12, CREEPING, *WANDERING, converging]) == \
        [(40, 4), (10, 2), (-1, 0), (-1, 0), (-1, 0), (-1, 0), (-1, 0)]
    assert _cycle_at([alternating], it0=8) == [(17, 2)]


def test_newton_cycle_options_out_of_range_are_refused(cut):
    # -newton_cycle and -newton_cycle_tol out of range: error.txt names the file and the option
    words = last_launch(cut)
    for opts, said in ((["-newton_cycle", "-1"], "mechanics.idp: -newton_cycle must be >= 0, got -1"),
                       (["-newton_cycle_tol", "1.5"], "mechanics.idp: -newton_cycle_tol must be in (0, 1), got 1.5")):
        with tempfile.TemporaryDirectory() as tmp:
            bad = newton_replay.replay(words, opts, keep=Path(tmp) / "bad")
            assert bad["exit"] == 3 and said in (Path(tmp) / "bad" / "error.txt").read_text()
