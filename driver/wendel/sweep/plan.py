"""Read a sweep file and plan its runs: one validated scene per parameter set, keyed by content.

A sweep file names a scene and a plan over its dotted keys::

    scene = "../smoke.toml"          # relative to the sweep file
    smoke = true                     # start from the scene's smoke size
    [grid]                           # every combination
    "material.E" = [1.0, 2.5]        # Pa
    [zip]                            # advanced together (equal lengths)
    "loading.steps" = [1, 2]         # 1
    [sample]                         # seeded random or Latin-hypercube samples in ranges
    method = "lhs"
    count = 4
    seed = 1
    ranges = {"material.nu" = [0.2, 0.3]}   # 1

The blocks present are combined as a product (grid points x zip rows x samples); ``[set]`` (key = value) is
applied to every run. Every planned scene is validated first; a bad one refuses the sweep naming key and values.

>>> points = grid_points({"a": [1, 2], "b": [3, 4]})
>>> [tuple(p.values()) for p in points]
[(1, 3), (1, 4), (2, 3), (2, 4)]
>>> (xs := [p["x"] for p in sample_points("lhs", 4, 1, {"x": [0.0, 1.0]})]) == sorted(xs)
False
>>> sorted(int(4 * p["x"]) for p in sample_points("lhs", 4, 1, {"x": [0.0, 1.0]}))
[0, 1, 2, 3]
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Literal, Optional

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from .. import __version__
from ..scene import SceneError, parse
from ..scene.reading import read_toml

SAMPLERS = {}


def sampler(name: str):
    """Register a sampler ``func(count, seed, dims) -> array (count, dims) in [0, 1)``."""

    def wrap(func):
        SAMPLERS[name] = func
        return func

    return wrap


@sampler("random")
def _random(count: int, seed: int, dims: int):
    import numpy as np

    return np.random.default_rng(seed).random((count, dims))


@sampler("lhs")
def _lhs(count: int, seed: int, dims: int):
    from scipy.stats import qmc

    return qmc.LatinHypercube(d=dims, seed=seed).random(count)


class Sample(BaseModel):
    """Seeded samples in ranges (uniform; integer ranges give integers)."""

    model_config = ConfigDict(extra="forbid")
    method: Literal[tuple(SAMPLERS)] = Field("lhs", description="random or lhs (Latin hypercube)")
    count: int = Field(..., ge=1, description="number of samples")
    seed: int = Field(0, description="seed of the generator: the same seed gives the same samples")
    ranges: dict = Field(..., description="dotted key = [low, high]")


class Slurm(BaseModel):
    """Resources of one task of a job array on SLURM (``runs_per_task`` runs, one after the other)."""

    model_config = ConfigDict(extra="forbid")
    partition: Optional[str] = Field(None, description="partition (default: the cluster's default)")
    time: int = Field(60, ge=1, description="time limit of one task [min]; past it the task is requeued")
    mem: str = Field("2G", description="memory of one task (sbatch --mem)")
    cpus_per_run: Optional[int] = Field(None, ge=1, description="CPUs of one run (default: its MPI ranks)")
    parallelism: int = Field(16, ge=1, description="tasks at a time (array parallelism)")
    runs_per_task: int = Field(1, ge=1, description="runs of one task, forked from one warm process (small runs)")


class SweepFile(BaseModel):
    """The sweep file's keys."""

    model_config = ConfigDict(extra="forbid")
    description: str = Field(..., min_length=1, description="one line saying what the campaign asks")
    scene: str = Field(..., description="scene file, relative to the sweep file")
    smoke: bool = Field(False, description="start from the scene's [smoke] size")
    grid: dict = Field(default_factory=dict, description="dotted key = [values]: every combination")
    zip: dict = Field(default_factory=dict, description="dotted key = [values]: lists advanced together")
    set: dict = Field(default_factory=dict, description="dotted key = value: set in every run, not swept")
    sample: Optional[Sample] = None
    outputs: list[str] = Field(default_factory=lambda: ["wall_time"],
                               description="summary.json keys (or last_increment keys) plotted against each parameter")
    workers: Optional[int] = Field(None, ge=1, description="local runs at a time (default cores / ranks per run)")
    slurm: Slurm = Slurm()


@dataclass
class Run:
    """One planned run: its parameters, the scene to run and the folder name keyed by content."""

    params: dict
    data: dict                 # the scene as TOML data (smoke size and parameters applied)
    resolved: dict             # the validated scene with every default (what the hash covers)
    key: str = ""
    ranks: int = 1


@dataclass
class Sweep:
    """A planned sweep."""

    path: Path
    spec: SweepFile
    scene_path: Path
    runs: list[Run] = field(default_factory=list)

    @property
    def keys(self) -> list[str]:
        return list(dict.fromkeys(k for r in self.runs for k in r.params))


def flatten(table: dict, prefix: str = "") -> dict:
    """``{"material": {"E": [1, 2]}}`` and ``{"material.E": [1, 2]}`` alike give ``{"material.E": [1, 2]}``.

    >>> flatten({"material": {"E": [1, 2]}, "geometry.h": [0.1]})
    {'material.E': [1, 2], 'geometry.h': [0.1]}
    """
    out = {}
    for k, v in table.items():
        if isinstance(v, dict):
            out.update(flatten(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def grid_points(grid: dict) -> list[dict]:
    keys = list(grid)
    return [dict(zip(keys, combo)) for combo in itertools.product(*(grid[k] for k in keys))]


def zip_points(table: dict) -> list[dict]:
    keys = list(table)
    return [dict(zip(keys, row)) for row in zip(*(table[k] for k in keys))]


def sample_points(method: str, count: int, seed: int, ranges: dict) -> list[dict]:
    keys = list(ranges)
    u = SAMPLERS[method](count, seed, len(keys))
    points = []
    for row in u:
        p = {}
        for k, x in zip(keys, row):
            lo, hi = ranges[k]
            if isinstance(lo, int) and isinstance(hi, int):
                p[k] = int(lo + math.floor(x * (hi - lo + 1)))
            else:
                p[k] = float(lo + x * (hi - lo))
        points.append(p)
    return points


def set_key(data: dict, dotted: str, value) -> None:
    """Set ``data[a][b][c] = value`` for ``a.b.c`` (tables made on the way)."""
    *parents, last = dotted.split(".")
    d = data
    for p in parents:
        d = d.setdefault(p, {})
        if not isinstance(d, dict):
            raise KeyError(dotted)
    d[last] = value


SMOKE_KEYS = {"h": "geometry.h", "steps": "loading.steps", "ranks": "numerics.ranks"}
"""What a scene's [smoke] table overrides (as ``wendel.scene.apply_smoke`` does)."""


@lru_cache(maxsize=1)
def freefem_version() -> str:
    from ..results.summary import _freefem_version

    return _freefem_version()


def content_key(resolved: dict) -> str:
    """Hash of the resolved scene, the wendel version and the FreeFEM version (12 hex digits).

    >>> len(content_key({"a": 1}))
    12
    """
    blob = json.dumps({"scene": resolved, "wendel": __version__, "freefem": freefem_version()}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:12]


def _short(v) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def folder_name(params: dict, digest: str) -> str:
    """Readable parameters and the content hash: ``E=2.5_h=0.1-0123456789ab``.

    >>> folder_name({"material.E": 2.5, "geometry.h": 0.1}, "0123456789ab")
    'E=2.5_h=0.1-0123456789ab'
    """
    text = "_".join(f"{k.rsplit('.', 1)[-1]}={_short(v)}" for k, v in params.items())
    text = "".join(c if c.isalnum() or c in "=._+-" else "-" for c in text)[:80]
    return f"{text}-{digest}" if text else digest


def load_sweep(path: str | Path) -> Sweep:
    """Read the sweep file, plan every run and validate every planned scene (SceneError names key and values)."""
    path = Path(path)
    try:
        spec = SweepFile.model_validate(read_toml(path, "sweep"))
    except ValidationError as exc:
        raise SceneError("\n".join(f"{path}: {'.'.join(map(str, e['loc']))}: {e['msg']}" for e in exc.errors())) from None
    scene_path = (path.parent / spec.scene).resolve()
    if not scene_path.is_file():
        raise SceneError(f"{path}: scene: no such scene file {scene_path}")
    base = read_toml(scene_path)
    parse(base, str(scene_path))                              # the scene itself must be valid
    if spec.smoke:
        for k, v in (base.get("smoke") or {}).items():
            set_key(base, SMOKE_KEYS[k], v)
    for k, v in (fixed := flatten(spec.set)).items():        # [set]: the same in every run, not a parameter
        try:
            set_key(base, k, v)
        except KeyError:
            raise SceneError(f"{path}: set.{k}: not a table of the scene") from None
    if isinstance(base.get("geometry", {}).get("mesh"), str):  # a mesh file stays found from anywhere
        base["geometry"]["mesh"] = str((scene_path.parent / base["geometry"]["mesh"]).resolve())

    blocks = []
    grid, zipped = flatten(spec.grid), flatten(spec.zip)
    for name, table in (("grid", grid), ("zip", zipped)):
        for k, v in table.items():
            if not isinstance(v, list) or not v:
                raise SceneError(f"{path}: {name}.{k}: give a non-empty list of values")
    if grid:
        blocks.append(grid_points(grid))
    if zipped:
        lengths = {k: len(v) for k, v in zipped.items()}
        if len(set(lengths.values())) > 1:
            raise SceneError(f"{path}: zip: lists of different lengths: "
                             + ", ".join(f"{k} ({n})" for k, n in lengths.items()))
        blocks.append(zip_points(zipped))
    if spec.sample is not None:
        ranges = flatten(spec.sample.ranges)
        for k, v in ranges.items():
            if not (isinstance(v, list) and len(v) == 2 and all(isinstance(x, (int, float)) for x in v) and v[0] < v[1]):
                raise SceneError(f"{path}: sample.ranges.{k}: give [low, high] with low < high")
        blocks.append(sample_points(spec.sample.method, spec.sample.count, spec.sample.seed, ranges))
    seen: dict[str, str] = {k: "set" for k in fixed}
    for name, table in (("grid", grid), ("zip", zipped), ("sample", flatten(spec.sample.ranges) if spec.sample else {})):
        for k in table:
            if k in seen:
                raise SceneError(f"{path}: {name}.{k}: the key is already swept in [{seen[k]}]")
            seen[k] = name
    if not blocks:
        raise SceneError(f"{path}: nothing to sweep: give [grid], [zip] or [sample]")

    sweep = Sweep(path=path.resolve(), spec=spec, scene_path=scene_path)
    keys = set()
    for combo in itertools.product(*blocks):
        params = {k: v for point in combo for k, v in point.items()}
        data = copy.deepcopy(base)
        for k, v in params.items():
            try:
                set_key(data, k, v)
            except KeyError:
                raise SceneError(f"{path}: {k}: not a table of the scene") from None
        where = ", ".join(f"{k} = {_short(v)}" for k, v in params.items())
        try:
            scene = parse(data, f"{path} (run {len(sweep.runs) + 1}: {where})")
        except SceneError as exc:
            raise SceneError(str(exc).replace(f"{scene_path}: ", "")) from None
        resolved = scene.model_dump(mode="json")
        run = Run(params=params, data=data, resolved=resolved, ranks=scene.numerics.ranks)
        run.key = folder_name(params, content_key(resolved))
        if run.key in keys:
            raise SceneError(f"{path}: run {len(sweep.runs) + 1} ({where}) is the same scene as an earlier run")
        keys.add(run.key)
        sweep.runs.append(run)
    return sweep
