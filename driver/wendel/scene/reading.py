"""Read a scene file (TOML) into a validated :class:`wendel.scene.schema.Scene`.

Errors name the file and the key: ``workflows/x.toml: material.E: Input should be greater than 0``.
Validation is strict (booleans and strings are not numbers, a float is not an integer); every number
anywhere in the file must be finite and at most :data:`LIMIT` in magnitude; builder parameters, boundary
names, a mesh file and the size of the problem are checked before anything is meshed or solved.

>>> from pathlib import Path
>>> s = load(Path(__file__).parents[3] / "workflows" / "smoke.toml")
>>> s.material.E > 0
True
"""

from __future__ import annotations

import copy
import inspect
import math
import tomllib
from pathlib import Path

from pydantic import ValidationError

from ..meshes import LABELS
from ..meshes.builders import BOUNDARIES, BUILDERS
from ..meshes.check import inspect_file
from ..meshes.params import estimate_elements, validate as validate_builder
from .schema import Scene

# Cell fields every mechanics run writes, and those of the blocks (remesh.indicator names one of them).
CELL_FIELDS = ("vonMises", "strain_xx", "strain_yy", "strain_zz", "strain_xy", "strain_xz", "strain_yz")
BLOCK_CELL_FIELDS = ("p", "sigma_y", "plastic", "epsp_xx", "epsp_yy", "epsp_zz", "epsp_xy", "T", "mean_stress")

# Largest magnitude of a number in a scene: beyond it products such as tgv * value or a squared stress
# overflow in double precision (1e30 * 1e30 * 1e30 < 1.8e308).
LIMIT = 1e30


class SceneError(Exception):
    """A scene file that cannot be run; the message names the file and the key."""


def _loc(loc) -> str:
    return ".".join(str(p) for p in loc if not str(p).startswith("function-after"))


def _numbers(data, source: str, key: str = "") -> None:
    """Refuse non-finite numbers and magnitudes beyond LIMIT anywhere in ``data``, naming the key."""
    items = data.items() if isinstance(data, dict) else enumerate(data) if isinstance(data, list) else ()
    for k, v in items:
        sub = (f"{key}.{k}" if key else str(k)) if isinstance(data, dict) else key
        if isinstance(v, (dict, list)):
            _numbers(v, source, sub)
        elif isinstance(v, (int, float)) and not isinstance(v, bool):
            if isinstance(v, float) and not math.isfinite(v):
                raise SceneError(f"{source}: {sub}: {v!r} is not a finite number")
            if abs(v) > LIMIT:
                raise SceneError(f"{source}: {sub}: {v:.3g} is beyond the magnitude wendel accepts ({LIMIT:g})")


def parse(data: dict, source: str = "<scene>") -> Scene:
    """Validate a scene given as a dict (``source`` names it in error messages)."""
    _numbers(data, source)
    try:
        scene = Scene.model_validate(data, strict=True)
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
    g = scene.geometry
    if g.builder is not None:
        try:
            params = validate_builder(g.builder, g.params)
        except ValueError as exc:
            raise SceneError(f"{source}: geometry.{exc}") from None
        g.model_extra.update({k: v for k, v in params.items() if k != "h"})
        if g.builder in BOUNDARIES:
            named = BOUNDARIES[g.builder](**params)
            for key, name in boundary_names(scene):
                if name not in named:
                    raise SceneError(f"{source}: {key}: builder {g.builder!r} names {', '.join(named)}")
    check_size(scene, source)
    _indicator(scene, source)
    return scene


def boundary_names(scene: Scene) -> list[tuple[str, str]]:
    """(key, boundary name) of every condition the scene puts on a named boundary."""
    keys = [(f"boundary.{n}", n) for n in scene.boundary]
    thermal = getattr(scene, "thermal", None)
    if thermal is not None:
        keys += [(f"thermal.boundary.{n}", n) for n in thermal.boundary]
    trim = scene.remesh.trim if scene.remesh is not None else None
    if trim is not None:
        keys.append(("remesh.trim.label", trim.label))
    return keys


def check_size(scene: Scene, source: str) -> None:
    """Refuse a scene whose mesh or load path would exhaust the machine, before anything is built."""
    n, g = scene.numerics, scene.geometry
    if g.builder is not None:
        est = estimate_elements(g.builder, validate_builder(g.builder, g.params))
        if est is not None and est > n.max_elements:
            # the sizes the estimate used, defaults included (a deleted radius falls back to its default)
            sig = inspect.signature(BUILDERS[g.builder]).parameters
            sizes = {k: v.default for k, v in sig.items() if k not in ("path", "h", "refine")
                     and isinstance(v.default, (int, float, tuple)) and not isinstance(v.default, bool)}
            sizes.update({k: v for k, v in g.params.items() if k in sizes})
            used = ", ".join(f"{k} = {list(v) if isinstance(v, tuple) else v}" for k, v in sizes.items())
            refine = g.params.get("refine")
            if refine:
                used += f", refined zone {', '.join(f'{k} = {v}' for k, v in refine.items())}"
            raise SceneError(
                f"{source}: geometry.h: the mesh would have about {est:.2g} elements (estimated from h = {g.h:g} "
                f"and the geometry: {used}), above numerics.max_elements = {n.max_elements:.3g}: use a larger h, "
                f"or raise numerics.max_elements if this machine can hold it")
    loading = scene.loading
    count, key = (len(loading.factors), "loading.factors") if loading.factors else (loading.steps, "loading.steps")
    if count > n.max_increments:
        raise SceneError(f"{source}: {key}: {count} increments, above numerics.max_increments = "
                         f"{n.max_increments}: raise numerics.max_increments if you mean it")


def _indicator(scene: Scene, source: str) -> None:
    """remesh.indicator must be a cell field the run writes (it names a file of the increment folder)."""
    from .blocks import BLOCKS

    if scene.remesh is None or not scene.remesh.indicator:
        return
    valid = list(CELL_FIELDS) + [
        f for name in scene.blocks for f in BLOCKS[name].fields if f in BLOCK_CELL_FIELDS]
    if scene.elasticity.plane == "axisymmetric":
        valid.append("strain_hoop")            # the hoop strain of (r, z) models (edp/lib/mechanics.idp)
    if scene.remesh.indicator not in valid:
        writers = [f"[{name}]" for name, b in BLOCKS.items() if scene.remesh.indicator in b.fields]
        why = f" (it is written by {' or '.join(writers)}, which this scene does not have)" if writers else ""
        raise SceneError(f"{source}: remesh.indicator: {scene.remesh.indicator!r} is not a cell field of this "
                         f"scene{why}; valid: {', '.join(valid)} (or \"\" for a uniform size)")


def read_toml(path: Path, what: str = "scene") -> dict:
    """The TOML file ``path`` (a ``what`` file) as a dict; SceneError naming the file otherwise."""
    if not path.is_file():
        raise SceneError(f"{path}: no such {what} file")
    try:
        return tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise SceneError(f"{path}: not valid TOML: {exc}") from None


def load(path: str | Path, smoke: bool = False) -> Scene:
    """Read and validate the scene file ``path``; with ``smoke`` apply its [smoke] overrides."""
    path = Path(path)
    scene = parse(read_toml(path), str(path))
    if scene.geometry.mesh is not None:
        mesh = (path.parent / scene.geometry.mesh).resolve()
        if not mesh.is_file():
            raise SceneError(f"{path}: geometry.mesh: no such file {mesh}")
        try:
            info = inspect_file(mesh)
        except ValueError as exc:
            raise SceneError(f"{path}: geometry.mesh: {exc}") from None
        if info.dimension != scene.geometry.dimension:
            raise SceneError(f"{path}: geometry.dimension: {scene.geometry.dimension}, but {mesh} holds a "
                             f"{info.dimension}D mesh")
        tags = info.tags.get(info.dimension - 1, set())
        for key, name in boundary_names(scene):
            if LABELS[name] not in tags:
                have = ", ".join(f"{t} ({info.names.get(t, '?')})" for t in sorted(tags))
                raise SceneError(f"{path}: {key}: the mesh file {mesh} has no physical tag {LABELS[name]} "
                                 f"({name}); its boundary tags: {have}")
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
