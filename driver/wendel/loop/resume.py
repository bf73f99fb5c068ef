"""Continuing a run from its folder: from the last checkpoint (accepting what FreeFEM committed after it,
finishing an interrupted re-equilibration, stopping a FreeFEM launch that outlived its driver), or from the
start when it stopped before its first checkpoint; a drilling run after its last completed removal step.
"""

from __future__ import annotations

import contextlib
import json
import shutil
import tempfile
from pathlib import Path

from ..results import summary
from ..scene.schema import Scene
from .checkpoint import RunFiles, State, load_state, save as _save_checkpoint
from .guard import guarded, stop_leftovers


def restart(root: Path, progress) -> Path:
    """A run stopped before its first checkpoint (while meshing): nothing was computed, so it starts again
    in its own folder from the scene it saved there."""
    from .quasistatic import run_scene

    scene = Scene.model_validate(json.loads((root / "scene.resolved.json").read_text()))
    smoke = False
    with contextlib.suppress(OSError, ValueError, KeyError):
        smoke = bool(json.loads((root / "provenance.json").read_text())["smoke"])
    progress(f"resuming {root}: it stopped before its first increment; starting it again")
    with tempfile.TemporaryDirectory() as tmp:
        source = Path(tmp) / "scene.toml"
        if (root / "scene.toml").is_file():
            shutil.copyfile(root / "scene.toml", source)
        else:
            source.write_text("# the scene file was not saved before the run stopped; see scene.resolved.json\n")
        for p in root.iterdir():
            shutil.rmtree(p) if p.is_dir() else p.unlink()
        return run_scene(scene, source, root, smoke, progress)


def resume(root: Path, progress=print) -> tuple[RunFiles, Scene, State]:
    from .quasistatic import _reequilibrated, accept

    files, scene, state, dimension = load_state(root)
    if stop_leftovers(files.fem):
        progress(f"  stopped a FreeFEM launch of {root} that outlived its driver")
    # An increment committed after the last checkpoint is taken as it is; a partial one is dropped.
    summary.truncate_history(files.root, state.last[0])
    accept(scene, files, state, dimension)
    if state.reequilibrate and state.accepted and state.last[0] >= state.segments[-1]["first"]:
        _reequilibrated(files, state, progress)      # stopped after the re-equilibration was committed
        _save_checkpoint(files, scene, state, dimension)
    nxt = files.fem / f"inc-{state.last[0] + 1:04d}"
    if nxt.is_dir():
        shutil.rmtree(nxt)
    return files, scene, state


def resume_drilling(root: Path, progress) -> Path:
    """A drilling run goes on after its last completed removal step; stopped before its first, it starts again."""
    from . import drilling, drilling_state

    if not drilling_state.resumable(root):
        return restart(root, progress)
    scene = Scene.model_validate(json.loads((root / "scene.resolved.json").read_text()))
    smoke = bool(json.loads((root / "provenance.json").read_text()).get("smoke", False))
    with guarded(root):
        return drilling.run(scene, root / "scene.toml", root, smoke, progress, resume=True)


def is_drilling(root: Path) -> bool:
    """Whether the run folder holds a drilling run (its resolved scene has a [drilling] table)."""
    try:
        return json.loads((root / "scene.resolved.json").read_text()).get("drilling") is not None
    except (OSError, ValueError):
        return False
