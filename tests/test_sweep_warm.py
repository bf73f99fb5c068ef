"""Warm starts of a local sweep (`wendel.sweep.warm`, issue 20): the runs forked from one server that imported
the driver and the picture's modules once give the same runs as fresh interpreters."""

from __future__ import annotations

import csv
import json
import subprocess

import pytest

from test_sweep import sweep_file

from wendel.sweep import load_sweep, run_sweep
from wendel.sweep.folders import run_dir

WALL = {"run_wall", "wall_time"}


def _table(out) -> dict:
    return {r["key"]: {k: v for k, v in r.items() if k not in WALL} for r in csv.DictReader((out / "sweep.csv").open())}


def test_forked_runs_give_the_same_runs_files_and_failures(tmp_path, monkeypatch):
    """Three smoke runs, one stopped by its time limit: forked (default) and as subprocesses
    (``WENDEL_SWEEP_WARM=0``) the same table but for the wall times, byte-identical pictures, the same failure
    message; each done run's sweep.json says how it was started; no server is left."""
    sweep = sweep_file(tmp_path, '[zip]\n"material.E" = [1.0, 2.0, 3.0]   # Pa\n'
                       '"numerics.timeout" = [600.0, 0.01, 600.0]   # s\n')
    keys = [r.key for r in load_sweep(sweep).runs]
    reps = {}
    for warm in ("1", "0"):
        monkeypatch.setenv("WENDEL_SWEEP_WARM", warm)
        reps[warm] = run_sweep(sweep, out=tmp_path / warm, workers=2, quiet=True)
    for warm, rep in reps.items():
        got = {r["key"]: r for r in rep["rows"]}
        assert [got[k]["status"] for k in keys] == ["done", "failed", "done"], rep["rows"]
        assert "time limit of 0.01 s" in got[keys[1]]["message"]
        for k in (keys[0], keys[2]):
            assert json.loads((run_dir(tmp_path / warm, k) / "sweep.json").read_text())["warm"] is (warm == "1")
    assert _table(tmp_path / "1") == _table(tmp_path / "0")
    for k in (keys[0], keys[2]):
        png = [(run_dir(tmp_path / w, k) / "deformed.png").read_bytes() for w in ("1", "0")]
        assert len(png[0]) > 1000 and png[0] == png[1]
    left = subprocess.run(["pgrep", "-f", "wendel.sweep.warm import serve"], capture_output=True, text=True)
    assert left.returncode == 1, left.stdout


def test_a_gone_server_falls_back_and_a_bad_setting_is_refused(tmp_path, monkeypatch):
    """When the server has died the runs start as subprocesses (``spawn`` gives None); ``WENDEL_SWEEP_WARM``
    other than 0 or 1 is refused by name."""
    from wendel.sweep import warm

    server = warm.Warm()
    server.proc.kill()
    server.proc.wait()
    assert server.spawn(["--version"], tmp_path / "log") is None
    server.close()
    monkeypatch.setenv("WENDEL_SWEEP_WARM", "yes")
    with pytest.raises(ValueError, match="WENDEL_SWEEP_WARM = 'yes': 1"):
        run_sweep(sweep_file(tmp_path, '[zip]\n"material.E" = [1.0]   # Pa\n'), out=tmp_path / "out", quiet=True)
