"""Where a run stands and how it is kept on disk: the run folder's files, the state of the loop, checkpoint.json.

A run is resumable after every accepted increment: :func:`save` writes the scene (as validated), the
dimension and the :class:`State` atomically; :func:`load_state` reads them back.
"""

from __future__ import annotations

import itertools
import json
import os
import threading
from dataclasses import dataclass, field
from pathlib import Path

from ..results import vtu

from ..scene.schema import Scene


@dataclass
class RunFiles:
    """The folders and files of one run."""

    root: Path

    @property
    def fem(self) -> Path:
        return self.root / "fem"

    @property
    def tables(self) -> Path:
        return self.root / "tables"

    @property
    def vtu(self) -> Path:
        return self.root / "vtu"

    @property
    def mesh(self) -> Path:
        return self.root / "mesh.msh"

    @property
    def checkpoint(self) -> Path:
        return self.root / "checkpoint.json"


@dataclass
class State:
    """Where the run stands: accepted increments (number, load factor) and what is left to do."""

    accepted: list[tuple[int, float]] = field(default_factory=list)
    pending: list[float] = field(default_factory=list)
    cuts: int = 0
    # meshes of the run: from increment `first` on, mesh file, base displacement and pre-strain files
    segments: list[dict] = field(default_factory=lambda: [{"first": 1, "mesh": "mesh.msh", "ubase": None, "eps0": None}])
    remeshes: list[dict] = field(default_factory=list)
    reequilibrate: bool = False
    quality: dict = field(default_factory=dict)
    step: float | None = None        # adaptive loading: the current load-factor step
    launches: list[dict] = field(default_factory=list)
    mesh_seconds: float = 0.0
    post_seconds: float = 0.0
    behind_seconds: float = 0.0      # driver output done while FreeFEM solved (wendel.loop.overlap.Behind)

    @property
    def last(self) -> tuple[int, float]:
        return self.accepted[-1] if self.accepted else (0, 0.0)

    def segment(self, inc: int) -> dict:
        """The mesh segment increment ``inc`` belongs to."""
        return [s for s in self.segments if s["first"] <= inc][-1]


_SAVING = threading.RLock()
_SERIAL = itertools.count()


def save(files: RunFiles, scene: Scene, state: State, dimension: int) -> None:
    data = {"scene": scene.model_dump(mode="json"), "dimension": dimension,
            "accepted": state.accepted, "pending": state.pending, "cuts": state.cuts,
            "segments": state.segments, "remeshes": state.remeshes, "reequilibrate": state.reequilibrate,
            "quality": {str(k): v for k, v in state.quality.items()}, "step": state.step,
            "launches": state.launches, "mesh_seconds": state.mesh_seconds, "post_seconds": state.post_seconds,
            "behind_seconds": state.behind_seconds}
    # one line: json's C encoder (an indent takes its Python one: 4.3 against 0.7 ms a save of drilling-deep-rz's
    # 62 kB at its end, one save per increment; issue 20)
    text = json.dumps(data).encode()
    # One save at a time (the driver thread and the output thread of loop/overlap.py both save), each through a
    # temporary file of its own written unbuffered: a save interrupted by Ctrl-C or SIGTERM can then never write
    # into the checkpoint another save has put in place (measured once: checkpoint.json ended in 17 stray bytes).
    with _SAVING:
        tmp = files.checkpoint.with_suffix(f".{os.getpid()}.{next(_SERIAL)}.tmp")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        try:
            view = memoryview(text)
            while view:
                view = view[os.write(fd, view):]
        finally:
            os.close(fd)
        os.replace(tmp, files.checkpoint)


def load_state(root: Path) -> tuple[RunFiles, Scene, State, int]:
    """The run folder's files, scene, state and dimension as its checkpoint.json holds them."""
    files = RunFiles(root)
    if not files.checkpoint.is_file():
        raise FileNotFoundError(f"{root}: no checkpoint.json to resume from: the run stopped before it saved "
                                f"its scene; start it again with `wendel run SCENE --out {root}`")
    data = json.loads(files.checkpoint.read_text())
    scene = Scene.model_validate(data["scene"])
    state = State(accepted=[tuple(a) for a in data["accepted"]], pending=data["pending"], cuts=data["cuts"],
                  launches=data["launches"], mesh_seconds=data["mesh_seconds"], post_seconds=data["post_seconds"],
                  segments=data["segments"], remeshes=data["remeshes"], reequilibrate=data["reequilibrate"],
                  quality={int(k): v for k, v in data["quality"].items()}, step=data["step"],
                  behind_seconds=data.get("behind_seconds", 0.0))
    return files, scene, state, data["dimension"]


def committed(inc_dir: Path) -> dict | None:
    """The record of increment folder ``inc_dir`` if FreeFEM committed it whole (its `done` marker, a
    readable record.json and every array file complete), else None."""
    if not (inc_dir / "done").is_file():
        return None
    try:
        record = json.loads((inc_dir / "record.json").read_text())
    except (OSError, ValueError):
        return None
    arrays = [p for p in inc_dir.glob("*.txt")]
    return record if all(vtu.complete_array(p) for p in arrays) else None
