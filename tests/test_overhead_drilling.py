"""Time outside the solve of the drilling loop (issue 20): each launch started while the driver prepares it
(wendel.prestart), the next removal step's mesh built while FreeFEM solves (wendel.loop.ahead), each mesh
file parsed once (wendel.results.meshfile); the same run as without them (WENDEL_PRESTART=0). The point sets
located and the next mesh read beside the solve (wendel.loop.lookahead): the same files, bit for bit, as
without (WENDEL_LOOKAHEAD=0)."""

from __future__ import annotations

import json
import subprocess

import meshio
import numpy as np

from conftest import WORKFLOWS


def _records(run):
    """Every increment's record.json without FreeFEM's clocks."""
    out = []
    for f in sorted((run / "fem").glob("inc-*/record.json")):
        rec = json.loads(f.read_text())
        out.append({k: v for k, v in rec.items() if not k.startswith("time_")})
    return out


def test_drilling_with_launches_and_meshes_started_ahead_gives_the_same_run(tmp_path, monkeypatch):
    """drilling-rz (smoke: 3 removal steps, 6 cooling increments): with every launch after the first started
    ahead and every mesh after the first built in the worker, the records, VTU fields, mesh files, the
    energy bookkeeping and the resume state are those of the run without; no FreeFEM is left waiting."""
    from wendel.loop import run

    ahead = run(WORKFLOWS / "drilling-rz.toml", smoke=True, out=tmp_path / "ahead", progress=lambda *_: None)
    monkeypatch.setenv("WENDEL_PRESTART", "0")
    plain = run(WORKFLOWS / "drilling-rz.toml", smoke=True, out=tmp_path / "plain", png=False,
                progress=lambda *_: None)
    s1, s2 = (json.loads((r / "summary.json").read_text()) for r in (ahead, plain))
    steps = s1["drilling"]["process"]["removal_steps"]
    assert steps >= 3 and s1["launches"] == s2["launches"] == steps + 1
    assert s1["drilling"]["remesh"]["launches_started_ahead"] == s1["launches"] - 1      # all but the first
    assert s1["drilling"]["remesh"]["meshes_built_ahead"] == steps - 1
    assert s2["drilling"]["remesh"]["launches_started_ahead"] == s2["drilling"]["remesh"]["meshes_built_ahead"] == 0
    log = (ahead / "freefem.log").read_text()
    assert log.count("-DWITHGATE=1") == s1["launches"] - 1 and log.count("$ ") == s1["launches"]   # none stopped unused

    r1, r2 = _records(ahead), _records(plain)
    assert len(r1) == len(r2) == s1["increments"]
    for a, b in zip(r1, r2):
        assert a.keys() == b.keys()
        assert {k: v for k, v in a.items() if isinstance(v, str)} == {k: v for k, v in b.items() if isinstance(v, str)}
        nums = [k for k, v in a.items() if not isinstance(v, str)]
        np.testing.assert_allclose([a[k] for k in nums], [b[k] for k in nums], rtol=1e-9, atol=0)
    for f in sorted((ahead / "meshes").glob("*.msh")):
        assert f.read_bytes() == (plain / "meshes" / f.name).read_bytes(), f.name
    vtus = sorted((ahead / "vtu").glob("inc-*.vtu"))
    assert len(vtus) == s1["increments"]
    for f in vtus:
        m1, m2 = meshio.read(f), meshio.read(plain / "vtu" / f.name)
        np.testing.assert_array_equal(m1.points, m2.points)
        assert m1.point_data.keys() == m2.point_data.keys() and m1.cell_data.keys() == m2.cell_data.keys()
        for k in m1.point_data:
            np.testing.assert_allclose(m1.point_data[k], m2.point_data[k], rtol=1e-9, atol=1e-300)
        for k in m1.cell_data:
            np.testing.assert_allclose(m1.cell_data[k][0], m2.cell_data[k][0], rtol=1e-9, atol=1e-300)
    e1, e2 = s1["drilling"]["energy"], s2["drilling"]["energy"]
    np.testing.assert_allclose([e1[k] for k in sorted(e1)], [e2[k] for k in sorted(e2)], rtol=1e-9, atol=1e-12)
    k1, k2 = (json.loads((r / "drilling-state.json").read_text()) for r in (ahead, plain))
    assert k1.keys() == k2.keys()
    left = subprocess.run(["pgrep", "-f", f"FreeFem.*{ahead}"], capture_output=True, text=True).stdout.split()
    assert not left, left
    assert not list((ahead / "meshes").glob("*.part.msh"))
    import matplotlib.image
    img = matplotlib.image.imread(ahead / "probes.png")
    assert img[..., :3].std() > 0.01            # not blank


def test_drilling_with_the_lookahead_writes_the_same_files_bit_for_bit(tmp_path, monkeypatch):
    """drilling-3d (smoke): the next mesh taken from the worker and read, and the probes, the removed slice,
    the new nodes and the new quadrature points located in a thread while FreeFEM solves; the driver's own
    calls then get those answers (wendel.remesh.transfer.locate keeps them by the bytes of mesh and points).
    Every file the run writes but its clocks is the one of the run without the thread."""
    from wendel.loop import run

    look = run(WORKFLOWS / "drilling-3d.toml", smoke=True, out=tmp_path / "look", png=False, progress=lambda *_: None)
    monkeypatch.setenv("WENDEL_LOOKAHEAD", "0")
    plain = run(WORKFLOWS / "drilling-3d.toml", smoke=True, out=tmp_path / "plain", png=False,
                progress=lambda *_: None)
    s1, s2 = (json.loads((r / "summary.json").read_text()) for r in (look, plain))
    steps = s1["drilling"]["process"]["removal_steps"]
    assert steps >= 2 and s1["drilling"]["remesh"]["meshes_read_beside"] == steps - 1
    assert s2["drilling"]["remesh"]["meshes_read_beside"] == 0
    clocks = ("time", "seconds", "wall", "share", "lookahead", "meshes_read_beside")
    files = [f.relative_to(look) for f in sorted(look.rglob("*")) if f.is_file()
             and f.suffix in (".txt", ".vtu", ".msh", ".csv") and not f.name.startswith(("newton", "history", "drilling-steps"))]   # clocks in them
    assert len(files) > 50
    for f in files:
        assert (look / f).read_bytes() == (plain / f).read_bytes(), f

    def strip(x):
        if isinstance(x, dict):
            return {k: strip(v) for k, v in x.items() if not any(c in k for c in clocks)}
        return [strip(v) for v in x] if isinstance(x, list) else x

    d1, d2 = (json.loads((r / "drilling.json").read_text()) for r in (look, plain))
    assert strip(d1) == strip(d2)
    assert _records(look) == _records(plain)


def test_a_launch_started_ahead_with_other_options_is_stopped_and_the_asked_one_runs(tmp_path):
    """wendel.freefem.run given a launch started with other options stops it and runs the launch asked for;
    given the matching one, says "go" to it: FreeFEM reads nothing before (its options' file is written
    after the start) and the launch's clock starts at the gate."""
    from wendel import freefem, prestart

    script = tmp_path / "gate.edp"
    script.write_text('include "lib/common.idp"\n'
                      'string word; { ifstream f(getARGV("-in", "")); f >> word; }\n'
                      '{ ofstream f(outDir + "/said.txt"); f << word << " " << getARGV("-x", "") << endl; }\n')
    out, inp = tmp_path / "out", tmp_path / "in.txt"
    wrong = prestart.start(str(script), ["-in", str(inp), "-x", "1"], out)
    right = None
    try:
        inp.write_text("first\n")
        launch = freefem.run(str(script), ["-in", str(inp), "-x", "2"], out, started=wrong)
        assert wrong.proc.poll() is not None                     # stopped, not used
        assert "-DWITHGATE=1" not in launch.command
        assert (out / "said.txt").read_text().split() == ["first", "2"]
        right = prestart.start(str(script), ["-in", str(inp), "-x", "3"], out)
        inp.write_text("second\n")                                # written after the start: read after "go"
        launch = freefem.run(str(script), ["-in", str(inp), "-x", "3"], out, started=right)
        assert "-DWITHGATE=1" in launch.command
        assert (out / "said.txt").read_text().split() == ["second", "3"]
    finally:
        prestart.abandon(wrong)
        prestart.abandon(right)


def test_a_launch_started_early_waits_at_nice_19_and_runs_at_the_drivers_priority(tmp_path):
    """prestart.start(..., early=True) (the drilling loop: the next launch beside this one's solve): until
    "go" every thread of FreeFEM runs at nice 19; from "go" at the driver's priority (a command FreeFEM runs
    inherits it), and the launch gives the same file as one started late."""
    import os

    import pytest

    from wendel import freefem, prestart

    if not prestart.can_start_early():
        pytest.skip("this process may not raise a priority again (not root, no RLIMIT_NICE)")
    script = tmp_path / "gate.edp"
    script.write_text('include "lib/common.idp"\n'
                      'string word; { ifstream f(getARGV("-in", "")); f >> word; }\n'
                      'exec("ps -o ni= -p $PPID > " + outDir + "/nice.txt");\n'
                      '{ ofstream f(outDir + "/said.txt"); f << word << endl; }\n')
    out, inp = tmp_path / "out", tmp_path / "in.txt"
    early = prestart.start(str(script), ["-in", str(inp)], out, early=True)
    try:
        assert early is not None and early.nice == os.getpriority(os.PRIO_PROCESS, 0)
        import time
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:      # nice execs setpriv, which execs FreeFEM: the same pid
            # the program itself (argv[0]), not nice's or setpriv's arguments, which name FreeFEM too: nice has
            # not yet lowered its priority when its command line is already there (seen once in CI: nice 0)
            if "FreeFem" in open(f"/proc/{early.proc.pid}/cmdline").read().split("\0")[0]:
                break
            time.sleep(0.01)
        for tid in os.listdir(f"/proc/{early.proc.pid}/task"):
            assert os.getpriority(os.PRIO_PROCESS, int(tid)) == prestart.EARLY_NICE
        inp.write_text("early\n")
        launch = freefem.run(str(script), ["-in", str(inp)], out, started=early)
        assert launch.command[:3] == ["nice", "-n", str(prestart.EARLY_NICE - early.nice)]
        assert (out / "said.txt").read_text().split() == ["early"]
        assert int((out / "nice.txt").read_text()) == early.nice
    finally:
        prestart.abandon(early)
