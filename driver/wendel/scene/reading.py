"""Read a scene file (TOML) into a validated :class:`wendel.scene.schema.Scene`.

Errors name the file and the key: ``workflows/x.toml: material.E: Input should be greater than 0``.

>>> from pathlib import Path
>>> s = load(Path(__file__).parents[3] / "workflows" / "smoke.toml")
>>> s.material.E > 0
True
"""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

from pydantic import ValidationError

from ..meshes import LABELS
from .schema import Scene


class SceneError(Exception):
    """A scene file that cannot be run; the message names the file and the key."""


def _loc(loc) -> str:
    return ".".join(str(p) for p in loc if not str(p).startswith("function-after"))


def parse(data: dict, source: str = "<scene>") -> Scene:
    """Validate a scene given as a dict (``source`` names it in error messages)."""
    try:
        scene = Scene.model_validate(data)
    except ValidationError as exc:
        lines = []
        for err in exc.errors():
            key = _loc(err["loc"]) or "(top level)"
            msg = err["msg"].removeprefix("Value error, ")
            if err["type"] == "extra_forbidden":
                msg = "unknown key"
            lines.append(f"{source}: {key}: {msg}")
        raise SceneError("\n".join(lines)) from None
    for name in scene.boundary:
        if name not in LABELS:
            raise SceneError(f"{source}: boundary.{name}: unknown boundary name; valid: {', '.join(LABELS)}")
    return scene


def load(path: str | Path, smoke: bool = False) -> Scene:
    """Read and validate the scene file ``path``; with ``smoke`` apply its [smoke] overrides."""
    path = Path(path)
    if not path.is_file():
        raise SceneError(f"{path}: no such scene file")
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: not valid TOML: {exc}") from None
    scene = parse(data, str(path))
    if scene.geometry.mesh is not None:
        mesh = (path.parent / scene.geometry.mesh).resolve()
        if not mesh.is_file():
            raise SceneError(f"{path}: geometry.mesh: no such file {mesh}")
        scene.geometry.mesh = str(mesh)
    return apply_smoke(scene) if smoke else scene


def apply_smoke(scene: Scene) -> Scene:
    """A copy of ``scene`` at its declared smoke size."""
    s = copy.deepcopy(scene)
    if scene.smoke.h is not None:
        s.geometry.h = scene.smoke.h
    if scene.smoke.steps is not None:
        s.loading.steps = scene.smoke.steps
    if scene.smoke.ranks is not None:
        s.numerics.ranks = scene.smoke.ranks
    return s
