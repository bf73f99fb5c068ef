"""Campaigns: `wendel sweep` on the real FreeFEM, locally and through a real single-node SLURM."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import default_sigint

from wendel.scene import SceneError
from wendel.sweep import load_sweep, run_sweep, status
from wendel.sweep.folders import DONE, INTERRUPTED, run_dir, state

ROOT = Path(__file__).resolve().parents[1]
SMOKE = ROOT / "workflows" / "smoke.toml"
GRID = ROOT / "workflows" / "campaigns" / "smoke-grid.toml"
CLUSTER = ROOT / "scripts" / "slurm-local.sh"


def sweep_file(tmp_path: Path, body: str, name: str = "sweep.toml") -> Path:
    p = tmp_path / name
    p.write_text(f'description = "test sweep"\nscene = "{SMOKE}"\nsmoke = true\n' + body)
    return p


def wendel(*args, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "wendel.cli", *map(str, args)], capture_output=True, text=True, **kw)


def test_every_planned_scene_is_validated_first(tmp_path):
    """One bad combination refuses the whole sweep, naming the key and the values (exit 2), before any run."""
    bad = sweep_file(tmp_path, '[grid]\n"material.E" = [1.0, 2.0]\n"material.nu" = [0.3, 0.7]\n')
    with pytest.raises(SceneError, match=r"material.E = 1, material.nu = 0.7\): material.nu"):
        load_sweep(bad)
    out = wendel("sweep", bad, "--out", tmp_path / "out")
    assert out.returncode == 2 and "material.nu" in out.stderr and "Traceback" not in out.stderr
    assert not (tmp_path / "out" / "runs").exists()
    unknown = sweep_file(tmp_path, '[grid]\n"material.G" = [1.0]\n', "unknown.toml")
    assert "material.G: unknown key" in wendel("sweep", unknown).stderr
    uneven = sweep_file(tmp_path, '[zip]\n"material.E" = [1.0, 2.0]\n"material.nu" = [0.3]\n', "uneven.toml")
    assert "different lengths" in wendel("sweep", uneven).stderr


def test_plan_grid_zip_samples_and_content_keys(tmp_path):
    """A grid x zip x samples product; seeded samples repeat; folder names change with the resolved scene only."""
    body = ('[grid]\n"material.E" = [1.0, 2.0]\n[zip]\n"geometry.h" = [0.2, 0.1]\n"loading.steps" = [1, 2]\n'
            '[sample]\nmethod = "lhs"\ncount = 3\nseed = 7\nranges = {"material.nu" = [0.1, 0.4]}\n')
    a, b = load_sweep(sweep_file(tmp_path, body)), load_sweep(sweep_file(tmp_path, body, "again.toml"))
    assert len(a.runs) == 2 * 2 * 3 and a.keys == ["material.E", "geometry.h", "loading.steps", "material.nu"]
    assert [r.key for r in a.runs] == [r.key for r in b.runs]
    assert all(0.1 <= r.params["material.nu"] <= 0.4 for r in a.runs)
    assert sorted({int(3 * (r.params["material.nu"] - 0.1) / 0.3) for r in a.runs}) == [0, 1, 2]   # one per stratum
    assert len({r.key for r in a.runs}) == 12
    other = load_sweep(sweep_file(tmp_path, body.replace("seed = 7", "seed = 8"), "other.toml"))
    assert {r.key for r in other.runs}.isdisjoint({r.key for r in a.runs})
    assert a.runs[0].resolved["material"]["E"] == 1.0 and a.runs[0].resolved["geometry"]["h"] == 0.2


def test_local_grid_skips_done_runs_and_reruns_deleted_ones(tmp_path):
    """The 3 x 3 smoke grid: completes; a re-run has nothing to do (< 3 s); two deleted folders re-run, only those."""
    out = tmp_path / "grid"
    rep = run_sweep(GRID, out=out, workers=2, quiet=True)
    rows = {r["key"]: r for r in rep["rows"]}
    assert len(rows) == 9 and all(r["status"] == "done" for r in rows.values()), rep["rows"]
    assert len({r["dofs"] for r in rows.values()}) == 3                 # three mesh sizes
    energies = {(r["material.E"], r["geometry.h"]): r["strain_energy"] for r in rows.values()}
    assert energies[(1.0, 0.1)] == pytest.approx(2.5 * energies[(2.5, 0.1)], rel=1e-6)   # linear: energy ~ 1/E
    for png in ("strain_energy.png", "heatmap-strain_energy.png", "error_vs_runtime.png"):
        assert (out / png).stat().st_size > 1000
    table = (out / "sweep.csv").read_text()

    t0 = time.perf_counter()
    again = wendel("sweep", GRID, "--out", out, "--quiet")
    seconds = time.perf_counter() - t0
    assert again.returncode == 0, again.stderr
    assert "9/9 done (9 skipped as done)" in again.stdout
    assert seconds < 3.0, f"a re-run with nothing to do took {seconds:.2f} s"
    assert (out / "sweep.csv").read_text() == table

    gone = sorted(rows)[2:4]
    for key in gone:
        shutil.rmtree(run_dir(out, key))
    rep = run_sweep(GRID, out=out, workers=2, quiet=True)
    assert sorted(o["key"] for o in rep["outcomes"]) == gone and rep["skipped"] == 7
    assert all(o["status"] == DONE and o["action"] == "started" for o in rep["outcomes"])


def test_ctrl_c_leaves_a_resumable_sweep(tmp_path):
    """Ctrl-C stops every run (exit 130) keeping their checkpoints; the same command resumes them."""
    sweep = sweep_file(tmp_path, '[grid]\n"material.E" = [1.0, 2.0]\n"loading.steps" = [20]   # 1\n')
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "wendel.cli", "sweep", str(sweep), "--out", str(out),
                             "--workers", "2", "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=default_sigint)
    keys = [r.key for r in load_sweep(sweep).runs]
    deadline = time.time() + 90
    while time.time() < deadline:      # wait until both runs have committed increments
        if all(len(list((run_dir(out, k) / "fem").glob("inc-*/done"))) >= 2 for k in keys):
            break
        time.sleep(0.2)
    else:
        proc.kill()
        pytest.fail("the runs did not start")
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert [state(run_dir(out, k))[0] for k in keys] == [INTERRUPTED, INTERRUPTED]
    assert subprocess.run(["pgrep", "-f", "--", f"FreeFem.*{out}"], capture_output=True).returncode == 1   # no FreeFEM left
    rep = run_sweep(sweep, out=out, workers=2, quiet=True)
    assert sorted(o["action"] for o in rep["outcomes"]) == ["resumed", "resumed"]
    assert all(r["status"] == "done" and r["increments"] == 20 for r in rep["rows"])


def _cluster_unavailable() -> str | None:
    if os.geteuid() != 0:
        return "the local SLURM needs root (slurmd runs as root)"
    missing = [b for b in ("slurmctld", "slurmd", "slurmdbd", "sbatch", "sacct", "munged", "mariadbd")
               if shutil.which(b) is None]
    if missing:
        return f"missing {', '.join(missing)} (make test installs slurmctld slurmd slurm-client slurmdbd munge mariadb-server)"
    return None


@pytest.fixture(scope="module")
def slurm_cluster(tmp_path_factory):
    """A single-node SLURM with accounting, started by scripts/slurm-local.sh and stopped after the tests."""
    reason = _cluster_unavailable()
    if reason:
        pytest.skip(reason)
    d = tmp_path_factory.mktemp("cluster")
    old = os.environ.get("SLURM_CONF")
    start = subprocess.run(["bash", str(CLUSTER), "start", str(d)], capture_output=True, text=True, timeout=120)
    try:
        assert start.returncode == 0, start.stderr
        os.environ["SLURM_CONF"] = str(d / "etc" / "slurm.conf")
        yield d
    finally:
        if old is None:
            os.environ.pop("SLURM_CONF", None)
        else:
            os.environ["SLURM_CONF"] = old
        subprocess.run(["bash", str(CLUSTER), "stop", str(d)], capture_output=True, text=True, timeout=120)
        left = subprocess.run(["pgrep", "-f", str(d)], capture_output=True, text=True).stdout.split()
        assert not left, f"daemons left running: {left}"


def test_sweep_through_slurm_with_a_failing_run_and_a_killed_job(tmp_path, slurm_cluster):
    """submitit job arrays on a real SLURM: runs complete, a run's own failure keeps its message, a job killed
    by scancel while running is reported failed (not waited for), and a re-run goes through the scheduler again."""
    sweep = sweep_file(tmp_path, '[zip]\n"material.E" = [1.0, 2.0, 3.0, 4.0]   # Pa\n'
                       '"numerics.timeout" = [600.0, 600.0, 0.01, 600.0]   # s\n'
                       '"loading.steps" = [1, 40, 1, 1]   # 1\n[slurm]\ntime = 5\nmem = "500M"\nparallelism = 2\n')
    out = tmp_path / "out"
    keys = [r.key for r in load_sweep(sweep).runs]
    rep = run_sweep(sweep, out=out, executor="slurm", detach=True, quiet=True)
    assert sorted(rep["jobs"]) == sorted(keys)
    long_job = rep["jobs"][keys[1]]
    deadline = time.time() + 60
    while not (run_dir(out, keys[1]) / "checkpoint.json").is_file():
        assert time.time() < deadline, "the long run did not start"
        time.sleep(0.3)
    subprocess.run(["scancel", long_job], check=True)
    deadline = time.time() + 90
    while True:
        root, counts, rows = status(out)
        if not set(counts) - {"done", "failed"}:
            break
        assert time.time() < deadline, f"jobs still not over: {counts}"
        time.sleep(1)
    got = {r["key"]: r for r in rows}
    assert [got[k]["status"] for k in keys] == ["done", "failed", "failed", "done"]
    assert f"SLURM job {long_job}: CANCELLED" in got[keys[1]]["message"]
    assert "time limit of 0.01 s" in got[keys[2]]["message"]
    collected = wendel("sweep", "collect", out)
    assert collected.returncode == 1 and "2/4 done" in collected.stdout
    table = (out / "sweep.csv").read_text()
    assert table.count(",done,") == 2 and "CANCELLED" in table

    rerun = wendel("sweep", sweep, "--out", out, "--executor", "slurm", "--quiet")   # waits; failed ones again
    assert "2 failed before (re-run)" in rerun.stdout
    assert "3/4 done" in rerun.stdout, rerun.stdout + rerun.stderr      # the killed run now completes
    assert len(list((out / "failed").iterdir())) == 2                  # earlier attempts kept aside


def test_a_preempted_slurm_run_is_requeued_and_resumes_from_its_checkpoint(tmp_path, slurm_cluster):
    """SIGUSR2 (what SLURM sends before a time limit or a preemption) makes submitit requeue the job; the
    requeued job resumes the run from its checkpoint (`wendel run --resume`) and completes it."""
    sweep = sweep_file(tmp_path, '[zip]\n"loading.steps" = [30]   # 1\n[slurm]\ntime = 5\n')
    out = tmp_path / "out"
    key = load_sweep(sweep).runs[0].key
    job = run_sweep(sweep, out=out, executor="slurm", detach=True, quiet=True)["jobs"][key]
    deadline = time.time() + 60
    while len(list((run_dir(out, key) / "fem").glob("inc-*/done"))) < 3:
        assert time.time() < deadline, "the run did not start"
        time.sleep(0.2)
    subprocess.run(["scancel", "--signal=USR2", job], check=True)
    requeued = False
    deadline = time.time() + 180                         # generous: the test machine is shared
    record_path = run_dir(out, key) / "sweep.json"       # written by the job after `wendel run` ended
    while state(run_dir(out, key))[0] != DONE or not record_path.is_file():
        assert time.time() < deadline, "the requeued run did not complete"
        reason = subprocess.run(["squeue", "-h", "-j", job, "-o", "%r"], capture_output=True, text=True).stdout
        if "BeginTime" in reason and not requeued:       # requeued: start it in 10 s, not 2 min later
            requeued = True
            # not "now": slurmd refuses a credential issued in the second its job was requeued
            # ("Killing non-startable batch job: Job credential revoked", seen once in CI here)
            subprocess.run(["scontrol", "update", f"jobid={job}", "StartTime=now+10"], capture_output=True)
        time.sleep(0.5)
    assert requeued
    record = json.loads(record_path.read_text())
    assert record["action"] == "resumed"
    assert json.loads((run_dir(out, key) / "summary.json").read_text())["increments"] == 30
    log = (out / "logs" / f"{key}.log").read_text()
    assert log.count("$ ") == 2 and "resuming" in log


def test_every_campaign_example_plans():
    """workflows/campaigns/*.toml: each plans and validates every scene (no run)."""
    examples = sorted((ROOT / "workflows" / "campaigns").glob("*.toml"))
    assert len(examples) >= 3
    for path in examples:
        assert load_sweep(path).runs, path


def test_one_local_sweep_at_a_time_per_folder(tmp_path):
    """A second `wendel sweep` on a folder in use is refused (exit 2) before it starts any run."""
    import fcntl

    sweep = sweep_file(tmp_path, '[grid]\n"material.E" = [1.0]   # Pa\n')
    out = tmp_path / "out"
    out.mkdir()
    with open(out / ".lock", "w") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        second = wendel("sweep", sweep, "--out", out, "--quiet")
    assert second.returncode == 2 and "another wendel sweep is running" in second.stderr
    assert not any((out / "runs").iterdir())


def test_several_runs_in_one_slurm_task_are_forked_warm(tmp_path, slurm_cluster):
    """``slurm.runs_per_task = 2``: three runs in two tasks of one array (the first two share a job id and are
    forked from one warm process, the third runs alone as a subprocess), all done; 0 is refused by key."""
    sweep = sweep_file(tmp_path, '[zip]\n"material.E" = [1.0, 2.0, 3.0]   # Pa\n'
                       '[slurm]\ntime = 5\nmem = "1G"\nruns_per_task = 2\n')
    out = tmp_path / "out"
    keys = [r.key for r in load_sweep(sweep).runs]
    rep = run_sweep(sweep, out=out, executor="slurm", quiet=True)
    jobs = rep["jobs"]
    assert jobs[keys[0]] == jobs[keys[1]] != jobs[keys[2]], jobs
    assert [r["status"] for r in rep["rows"]] == ["done"] * 3, (rep["rows"], [p.read_text()[-2000:] for p in
                                                                      (out / "slurm").rglob("*.out")])
    # the sweep waits for each task's sweep.json (written after `wendel run` ended): the table has every wall time
    assert all(isinstance(r["run_wall"], float) and r["run_wall"] > 0 for r in rep["rows"]), rep["rows"]
    records = [run_dir(out, k) / "sweep.json" for k in keys]
    warm = [json.loads(p.read_text())["warm"] for p in records]
    assert warm == [True, True, False], [(out / "logs" / f"{k}.log").read_text()[-2000:] for k in keys]
    bad = wendel("sweep", sweep, "--out", tmp_path / "bad", "--executor", "slurm", "--runs-per-task", "0")
    assert bad.returncode == 2 and "runs_per_task" in bad.stderr, bad.stderr
