"""Every scene in workflows/ runs at its smoke size (what users' CI pipelines do with --smoke)."""

import json

import pytest

from wendel.loop import StepCutError, run

from conftest import WORKFLOWS

SCENES = sorted(p.name for p in WORKFLOWS.glob("*.toml"))


@pytest.mark.parametrize("name", SCENES)
def test_scene_runs_at_smoke_size(name, tmp_path):
    out = tmp_path / "run"
    try:
        run(WORKFLOWS / name, smoke=True, out=out, png=False, progress=lambda *_: None)
    except StepCutError as exc:
        # a scene that loads past a limit load on purpose ends with that clear outcome, increments kept
        assert "limit load reached" in str(exc), exc
    s = json.loads((out / "summary.json").read_text())
    assert s["increments"] >= 1
    assert (out / "results.pvd").is_file() and (out / "history.csv").is_file()
    for key, value in s["errors"].items():
        assert value == value, f"{name}: {key} is NaN"
