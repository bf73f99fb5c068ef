"""The command line and the README contract."""

import subprocess
import sys
from pathlib import Path

from wendel.cli import main
from wendel.scene.schema import KEYS_BEGIN, KEYS_END, keys_table

ROOT = Path(__file__).resolve().parents[1]


def test_readme_key_table_is_the_schema():
    text = (ROOT / "README.md").read_text()
    table = text.split(KEYS_BEGIN, 1)[1].split(KEYS_END, 1)[0].strip()
    assert table == keys_table(), "run: .venv/bin/wendel keys --update README.md"


def test_readme_lists_every_scene():
    text = (ROOT / "README.md").read_text()
    for scene in sorted((ROOT / "workflows").glob("*.toml")):
        assert f"`{scene.name}`" in text, f"README does not list {scene.name}"


def test_version_and_usage_errors(capsys):
    out = subprocess.run([sys.executable, "-m", "wendel.cli", "--version"], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.startswith("wendel ")
    assert main(["run", str(ROOT / "workflows" / "nope.toml")]) == 2
    assert "no such scene file" in capsys.readouterr().err


def test_run_failure_exit_code(tmp_path, scene_file, capsys):
    from conftest import SMOKE_SCENE

    # a tolerance below round-off cannot be met: every increment and every cut fails
    text = SMOKE_SCENE.replace("[numerics]", "[numerics]\nnewton_maxit = 3\nnewton_tol = 1e-300")
    text = text.replace("[loading]\nsteps = 1", "[loading]\nsteps = 1\nmax_cuts = 1")
    path = scene_file(text)
    assert main(["run", str(path), "--smoke", "--out", str(tmp_path / "r")]) == 1
    err = capsys.readouterr().err
    assert "even after 1 step halvings" in err and "0 accepted increments are kept" in err


def test_relative_run_folder(tmp_path, monkeypatch, capsys):
    # FreeFEM runs inside the run folder: a relative --out (and --resume) must still reach the mesh
    monkeypatch.chdir(tmp_path)
    scene = ROOT / "workflows" / "smoke-mms.toml"
    assert main(["run", str(scene), "--smoke", "--out", "rel/run"]) == 0
    assert (tmp_path / "rel" / "run" / "summary.json").is_file()
    assert main(["run", "--resume", "rel/run"]) == 0
    assert "rel/run" in capsys.readouterr().out


def test_bench_help_names_every_benchmark(capsys):
    import pytest

    from wendel.bench import BENCHES, OPT_IN, _load_plugins

    _load_plugins()
    with pytest.raises(SystemExit):
        main(["bench", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    readme = (ROOT / "README.md").read_text()
    for name in BENCHES:
        assert name in text and f"`{name}`" in readme, name
    assert OPT_IN <= set(BENCHES)


def test_bench_writes_into_the_folder_out_names(tmp_path, capsys):
    import json

    assert main(["bench", "oxley", "--quick", "--out", str(tmp_path / "b")]) == 0
    data = json.loads((tmp_path / "b" / "oxley.json").read_text())
    assert data["meta"]["name"] == "oxley" and data["rows"]
    assert str(tmp_path / "b") in capsys.readouterr().out


def test_run_prints_the_errors_against_the_reference(tmp_path, capsys):
    assert main(["run", str(ROOT / "workflows" / "smoke-mms.toml"), "--smoke", "--out", str(tmp_path / "m")]) == 0
    out = capsys.readouterr().out
    line = next(l for l in out.splitlines() if l.startswith("relative error against the analytic reference"))
    l2 = float(line.split("L2 ")[1].split(",")[0])
    assert 0 < l2 < 0.5                                  # relative, not the absolute L2 norm
    assert main(["run", str(ROOT / "workflows" / "hertz.toml"), "--smoke", "--out", str(tmp_path / "h")]) == 0
    assert "errors against the closed form: contact_size " in capsys.readouterr().out


def test_a_used_run_folder_is_refused(tmp_path, capsys):
    scene = str(ROOT / "workflows" / "smoke-mms.toml")
    out = tmp_path / "r"
    assert main(["run", scene, "--smoke", "--out", str(out)]) == 0
    before = (out / "summary.json").read_text()
    assert main(["run", scene, "--smoke", "--out", str(out)]) == 2
    assert "exists and is not empty" in capsys.readouterr().err
    assert (out / "summary.json").read_text() == before              # nothing of the first run is touched


def test_parallel_runs_of_one_scene_get_their_own_folders(tmp_path, monkeypatch):
    import wendel.loop.quasistatic as runmod

    monkeypatch.setattr(runmod, "RESULTS", tmp_path)
    dirs = [runmod._new_run_dir(Path("workflows/smoke.toml"), smoke=True) for _ in range(3)]
    assert len(set(dirs)) == 3 and all(d.is_dir() and not any(d.iterdir()) for d in dirs)
