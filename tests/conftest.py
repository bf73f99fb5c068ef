"""Shared fixtures: scene files written on the fly, and small runs of the real FreeFEM."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
WORKFLOWS = ROOT / "workflows"

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

SMOKE_SCENE = (WORKFLOWS / "smoke.toml").read_text()


@pytest.fixture
def scene_file(tmp_path):
    """Write a scene text to a file and return its path."""

    def write(text: str, name: str = "scene.toml") -> Path:
        p = tmp_path / name
        p.write_text(text)
        return p

    return write


@pytest.fixture
def quiet():
    """A progress callback that keeps the lines for inspection."""
    lines: list[str] = []
    return lines.append


def smoke_ball(out: Path, **numerics) -> Path:
    """Run step-42's ball (workflows/ball-indent.toml, contact + J2 plasticity, 3D) at its smoke size with the
    ``[numerics]`` keys given, without picture and VTU; return the run folder."""
    from wendel.loop import run_scene
    from wendel.scene import load

    path = WORKFLOWS / "ball-indent.toml"
    scene = load(path, smoke=True)
    for key, value in numerics.items():
        setattr(scene.numerics, key, value)
    scene.output.png = False
    scene.output.vtu = False
    return run_scene(scene, path, out, smoke=True, progress=lambda *_: None)


def kill_after_increment(scene: Path, out: Path, increment: int) -> None:
    """``wendel run SCENE --smoke --out OUT`` in a process of its own, SIGKILLed once its increment
    ``increment`` is done (the run must still be going then), and ``wendel run --resume OUT`` to its end."""
    import signal
    import subprocess
    import sys
    import time

    cmd = [sys.executable, "-m", "wendel.cli", "run"]
    p = subprocess.Popen(cmd + [str(scene), "--smoke", "--out", str(out)], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    while p.poll() is None and not (out / "fem" / f"inc-{increment:04d}" / "done").is_file():
        time.sleep(0.005)
    assert p.poll() is None, f"the run ended before its increment {increment} was done"
    p.send_signal(signal.SIGKILL)
    p.wait()
    r = subprocess.run(cmd + ["--resume", str(out)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr


def edit(text: str, old: str, new: str) -> str:
    """``text`` with its first ``old`` replaced by ``new`` (which must be there: a test edits what it means to)."""
    assert old in text, old
    return text.replace(old, new, 1)


# The material and drilling process of the drilling tests (grey cast iron, a 4 mm drill): scene text to follow
# each test's [geometry] and boundary tables; ``{extra}`` takes the test's own [drilling] keys.
IRON = """[material]
E = 110e9                # Pa
nu = 0.26                # 1
"""
IRON_THERMAL = """k = 48.0                 # W/m/K
rho = 7200.0             # kg/m^3
c = 500.0                # J/kg/K
alpha = 11.7e-6          # 1/K
"""


def drill_table(h_bore: float) -> str:
    """The [drilling] and [output] tables of the drilling tests (``{extra}`` left for str.format)."""
    return f"""[drilling]
diameter = 0.004         # m
feed = 0.1e-3            # m
speed = 2000.0           # 1/min
force = "given"
torque = 1.0             # N m
eta_w = 0.3              # 1
h_bore = {h_bore}          # m
{{extra}}
[output]
png = false
"""


def drill(tmp_path, template: str, extra: str, name: str):
    """Run the drilling scene ``template`` with the [drilling] keys ``extra``; (run folder, summary's drilling)."""
    import json

    from wendel.loop import run

    scene = tmp_path / f"{name}.toml"
    scene.write_text(template.format(extra=extra))
    root = run(scene, out=tmp_path / name, progress=lambda *_: None)
    return root, json.loads((root / "summary.json").read_text())["drilling"]


def default_sigint():
    """For ``preexec_fn``: a child started with SIGINT at its default, which Python turns into KeyboardInterrupt.
    A suite started in the background of a non-interactive shell (``cmd &``) inherits SIGINT ignored, and so
    would the runs and sweeps the tests stop with SIGINT (they would finish unstopped)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
