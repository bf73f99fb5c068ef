"""Benchmarks (``wendel bench [NAME ...] [--quick]``): speed and cost figures written to results/bench/.

A benchmark is a function registered with :func:`register` (module ``bench/<name>.py`` for
``wendel bench <name>``); it returns a list of rows (dicts) that
are written as ``results/bench/<name>.csv`` and ``.json`` together with the machine it ran on.
Ratios are always taken within one benchmark run.
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
import platform
import time
from pathlib import Path
from typing import Callable

from ..loop import RESULTS

BENCHES: dict[str, Callable[[bool, Path], list[dict]]] = {}
OPT_IN = {"step42-dealii", "step42-pair", "step42-accuracy", "meshcache", "ranks", "overhead", "gmsh3d", "cutting", "cutting-adiabatic", "cutting-isothermal", "cutting-mesh", "cutting-fbar", "cutting-steady", "cutting-steady-fbar", "cutting-steady-mesh", "direct", "cutting-levers", "cutting-paths", "cutting-long", "cutting-heat", "cutting-ti", "cutting-kienzle", "drilling-3d", "necking-fine", "sweep-warm"}
"""Run only when named: deal.II's step-42 needs extra Debian packages and 8 minutes; ``overhead`` runs
every scene (twice with WENDEL_BENCH_BASE); the FE cuts take about 4 minutes each, the whole 3D deep bore (``drilling-3d``) about 7, the finer and remeshed necking bars (``necking-fine``) about 3."""


def run_fresh(scene, path: Path, out: Path, smoke: bool = False) -> dict:
    """Run the validated ``scene`` (read from ``path``) quietly into ``out``, emptied first; its summary.json."""
    import shutil

    from ..loop import run_scene

    shutil.rmtree(out, ignore_errors=True)
    run_scene(scene, path, out, smoke=smoke, progress=lambda *_: None)
    return json.loads((out / "summary.json").read_text())


def env_flag(name: str, what: str) -> bool:
    """An on/off setting of a bench from the environment variable ``name``: 1 (``what``), 0 or unset (as the scene
    says); anything else refused by name."""
    v = os.environ.get(name, "0")
    if v not in ("0", "1"):
        raise ValueError(f"{name} = {v!r}: 1 ({what}) or 0 (as the scene says)")
    return v == "1"


def volumetric(default: str | None) -> str | None:
    """The cutting benches' ``cutting.volumetric`` from ``WENDEL_BENCH_FBAR``: 1 F-bar (``"fbar"``), 0 the P1 cell's
    own volume change (``"cell"``), unset ``default`` (the scene's: both cutting scenes say ``"cell"``); anything else refused by name."""
    v = os.environ.get("WENDEL_BENCH_FBAR")
    if v is None:
        return default
    if v not in ("0", "1"):
        raise ValueError(f"WENDEL_BENCH_FBAR = {v!r}: 1 (cutting.volumetric = \"fbar\"), 0 (\"cell\") or unset (as the scene says)")
    return "fbar" if v == "1" else "cell"


HEAT = {"isothermal": "no Taylor-Quinney heat, thermal.beta = 0", "conduction": 'thermal.coupling = "staggered"'}
"""``WENDEL_BENCH_HEAT`` of ``cutting-mesh`` and ``cutting-fbar`` (:func:`heat`): the heat of every case (unset:
the scene's adiabatic heating). Session 20: the adiabatic Johnson-Cook steel softens with its own heat, and on fine F-bar meshes
that flow localizes and inverts cells; without the heat, or with conduction, it does not (README)."""


def heat(scene) -> str:
    """Apply ``WENDEL_BENCH_HEAT`` to ``scene``; the case-name suffix (refused by name when unknown)."""
    v = os.environ.get("WENDEL_BENCH_HEAT")
    if v is None:
        return ""
    if v not in HEAT:
        raise ValueError(f"WENDEL_BENCH_HEAT = {v!r}: " + ", ".join(f"{k} ({w})" for k, w in HEAT.items())
                         + " or unset (the scene's adiabatic heating)")
    if v == "isothermal":
        scene.thermal.beta = 0.0
    else:
        scene.thermal.coupling = "staggered"
    return ", " + v


def edges(default: list[tuple[str, int, int]]) -> list[tuple[str, int, int]]:
    """``cutting-mesh``'s cases from ``WENDEL_BENCH_EDGES``: three whole numbers, the edge radius over the edge size
    (e.g. ``3,4,5``), cut at the scene's step, and optionally a fourth, the one of them cut at half the step (by
    default the coarsest); unset ``default`` (r/2, r/3, r/4, r/2 at half the step). Session 21: with conduction,
    F-bar's r/2 cut and r/2 and r/3 at half the step stop where r/3 to r/5 and r/4 at half the step run through."""
    v = os.environ.get("WENDEL_BENCH_EDGES")
    if v is None:
        return default
    words = v.split(",")
    try:
        d = [int(x) for x in words]
    except ValueError:
        d = []
    if len(d) not in (3, 4) or len(set(d[:3])) != 3 or not all(2 <= x <= 8 for x in d) or d[3:] and d[3] not in d[:3]:
        raise ValueError(f"WENDEL_BENCH_EDGES = {v!r}: three different whole numbers from 2 to 8, the edge radius "
                         "over the edge size (e.g. 3,4,5), and optionally one of them again, cut at half the step")
    half = d[3] if len(d) == 4 else min(d[:3])
    a, b, c = sorted(d[:3])
    return [(f"r/{a}", a, 1), (f"r/{c}", c, 1), (f"r/{b}", b, 1), (f"r/{half}, half step", half, 2)]


def cut_mm() -> float:
    """``WENDEL_BENCH_CUT_MM`` (default 2.4) [mm], refused by name outside (1.2, 20]."""
    mm = float(os.environ.get("WENDEL_BENCH_CUT_MM", "2.4"))
    if not 1.2 < mm <= 20.0:
        raise ValueError(f"WENDEL_BENCH_CUT_MM = {mm}: a length of cut in mm above 1.2 (cutting-steady's) and up to 20")
    return mm


def edge() -> int:
    """``WENDEL_BENCH_EDGE`` of the long cutting benches: the edge size r / that whole number (2-8), default 2 (r/2);
    anything else refused by name. Session 21: with conduction F-bar needs r/3 or finer (README)."""
    v = os.environ.get("WENDEL_BENCH_EDGE", "2")
    if not (v.isdigit() and 2 <= int(v) <= 8):
        raise ValueError(f"WENDEL_BENCH_EDGE = {v!r}: a whole number from 2 to 8, the edge radius over the edge size")
    return int(v)


@contextlib.contextmanager
def environ(**values: str):
    """Set environment variables for the ``with`` block, each restored (or removed) after it.

    >>> with environ(WENDEL_DOCTEST_X="1"):
    ...     os.environ["WENDEL_DOCTEST_X"]
    '1'
    >>> "WENDEL_DOCTEST_X" in os.environ
    False
    """
    old = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def register(name: str):
    """Register a benchmark ``func(quick, workdir) -> rows`` under ``name``."""

    def wrap(func):
        BENCHES[name] = func
        return func

    return wrap


def bench(names: list[str] | None = None, quick: bool = False, out: Path | None = None, progress=print) -> Path:
    """Run the named benchmarks (by default all but those of ``OPT_IN``); return the folder with their results."""
    _load_plugins()
    names = names or sorted(n for n in BENCHES if n not in OPT_IN)
    unknown = [n for n in names if n not in BENCHES]
    if unknown:
        raise KeyError(f"unknown benchmark(s) {', '.join(unknown)}; valid: {', '.join(sorted(BENCHES))}")
    root = Path(out) if out else RESULTS / "bench"
    root.mkdir(parents=True, exist_ok=True)
    for name in names:
        progress(f"bench {name} ...")
        t0 = time.perf_counter()
        rows = BENCHES[name](quick, root / "work" / name)
        meta = {"name": name, "quick": quick, "seconds": time.perf_counter() - t0, "cpus": os.cpu_count(),
                "platform": platform.platform(), "date": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
        (root / f"{name}.json").write_text(json.dumps({"meta": meta, "rows": rows}, indent=1))
        if rows:
            keys = list(dict.fromkeys(k for r in rows for k in r))
            with open(root / f"{name}.csv", "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=keys)
                w.writeheader()
                w.writerows(rows)
            progress(_table(rows))
    return root


def _table(rows: list[dict]) -> str:
    keys = list(dict.fromkeys(k for r in rows for k in r))
    fmt = lambda v: f"{v:.4g}" if isinstance(v, float) else str(v)
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    lines += ["| " + " | ".join(fmt(r.get(k, "")) for k in keys) + " |" for r in rows]
    return "\n".join(lines)


def _load_plugins() -> None:
    """Import every benchmark module of this package (``bench/<name>.py``; each registers itself)."""
    import importlib
    import pkgutil

    for info in pkgutil.iter_modules(__path__):
        importlib.import_module(f"{__name__}.{info.name}")


WORKFLOWS = Path(__file__).resolve().parents[3] / "workflows"
