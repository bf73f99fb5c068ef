"""Benchmark ``overhead`` (issue 20): every second outside the solve, scene by scene.

Each scene of workflows/ is run as its own ``python`` process (so Python's start-up and imports count), as
``wendel run`` runs it (``wendel.cli.main``: the picture process started before the driver's imports; a scene
of :data:`SCALE` through ``wendel.loop.run`` with its h multiplied), and
its phases are read from the run's summary.json (:func:`shares`): FreeFEM start-up (launch wall time minus
FreeFEM's clock: process and MPI start, compiling the .edp, plugins), meshing (gmsh), FreeFEM file output
(the fields, energies and record of each increment), FreeFEM set-up (FreeFEM's clock outside solve and
output: reading the mesh, building spaces and state), driver output (VTU, histories, checkpoints left when
FreeFEM ends), remeshing and transfer, picture (the wait for the PNG) and Python (the process minus the
run: interpreter start, imports, provenance). "solve" is assembly + linear solve + constitutive update;
``outside_process`` is the share of the whole process outside it, which :func:`goal` holds against issue
20's goal; ``without_startup`` and ``warm`` (:func:`bounds`) what it would be with no FreeFEM start, and with
no Python start and imports either: the most that processes living across runs could give.

``--quick``: every scene at its smoke size. Otherwise each scene at its default size, except those of
:data:`SCALE` (their default takes minutes on the shared 2-core machine): geometry.h multiplied as stated.
``WENDEL_BENCH_SCENES=smoke,hertz``: a subset; ``WENDEL_BENCH_TIMEOUT``: seconds per run (600).

Before/after side by side: ``WENDEL_BENCH_BASE=/path/to/an/older/checkout wendel bench overhead`` runs each
scene with that checkout's driver too (same Python, alternating, one run each); the rows say which
(``tree``: ``base`` or ``this``) and ``same_as_base`` says whether both gave the same fingerprints
(:func:`same_fingerprints`). ``python -m wendel.bench.overhead RUN.json ...`` prints the table of saved runs
(:func:`side_by_side`). An older checkout's summary.json is read with today's accounting (:func:`shares`).
Both trees run this tree's scene file, unless ``WENDEL_BENCH_OWN_SCENES=1``: then the base runs its own
``workflows/`` file of the same name (a change of a scene's keys, e.g. hertz-force-3d's mesh options).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

from . import WORKFLOWS, register

SCALE = {"hertz-3d.toml": 2.0, "ball-indent.toml": 1.5, "stamp-indent.toml": 1.5}
"""Default-size scenes run coarser here (h multiplied): at their default they take minutes on this machine."""

SOLVE = ("assembly", "linear_solve", "constitutive")
THIS = Path(__file__).resolve().parents[3]
"""The checkout this module belongs to."""

_CHILD = """
import sys
from pathlib import Path
tree, scene, out, smoke, scale = sys.argv[1:6]
if tree:
    sys.path.insert(0, str(Path(tree) / "driver"))
if not scale:           # what a user runs: `wendel run SCENE --out DIR [--smoke]` (since session 34)
    from wendel.cli import leave, main
    leave(main(["run", scene, "--out", out] + (["--smoke"] if smoke == "1" else [])))
from wendel.loop import run
run(scene, smoke=smoke == "1", out=Path(out), progress=lambda *a: None, scale=float(scale))
try:                                      # the end of the wendel console script (a checkout that has it)
    from wendel.cli import leave
except ImportError:
    leave = sys.exit
leave(0)
"""


def scene_for(tree: Path | None, scene: Path) -> Path:
    """The scene file a tree runs: this tree's, or with ``WENDEL_BENCH_OWN_SCENES=1`` the base tree's own file
    of that name where it has one."""
    own = tree / "workflows" / scene.name if tree else scene
    return own if os.environ.get("WENDEL_BENCH_OWN_SCENES") == "1" and own.is_file() else scene


def run_once(scene: Path, out: Path, smoke: bool, scale: float | None, tree: Path | None = None) -> dict:
    """Run ``scene`` in a fresh Python process (the driver of checkout ``tree``, or this one); its row."""
    shutil.rmtree(out, ignore_errors=True)
    # this tree's driver named explicitly too: a copy of the checkout benchmarks its own code
    cmd = [sys.executable, "-c", _CHILD, str(tree or THIS), str(scene), str(out), "1" if smoke else "0",
           "" if scale is None or smoke else repr(scale)]
    load = os.getloadavg()[0]
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=tree or THIS,
                              timeout=float(os.environ.get("WENDEL_BENCH_TIMEOUT", "600")))
    except subprocess.TimeoutExpired:
        return {"scene": scene.stem, "size": "smoke" if smoke else "default", "tree": "base" if tree else "this",
                "process_wall": time.perf_counter() - t0, "error": "timeout (WENDEL_BENCH_TIMEOUT)"}
    process = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    # CPU seconds of the run's process and of all it waited for (FreeFEM, the picture process)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    row = {"scene": scene.stem, "size": "smoke" if smoke else (f"h x{scale:g}" if scale else "default"),
           "tree": "base" if tree else "this", "load_average": round(load, 1), "process_wall": process,
           "cpu": round(cpu, 3)}
    if proc.returncode != 0 or not (out / "summary.json").is_file():
        row["error"] = (proc.stderr.strip().splitlines() or ["?"])[-1][:200]
        return row
    return {**row, **shares(out)}


def shares(root: Path) -> dict:
    """The phases of the run in ``root`` in seconds, and the share of its wall time outside the solve.

    The same accounting for every driver: remeshing and transfer are a phase (an older summary.json has them
    only in its ``remeshes``), and an older driver's launch wall time included its accept of the
    increments (counted twice, as start-up and as driver output: taken out of the start-up here; a summary
    with ``driver_output_behind`` has the new accounting).

    >>> import tempfile; d = Path(tempfile.mkdtemp())
    >>> ph = {"mesh": 1.0, "freefem_startup": 1.0, "assembly": 2.0, "linear_solve": 4.0, "constitutive": 0.0,
    ...       "freefem_output": 0.5, "freefem_other": 0.5, "driver_output": 0.5, "picture": 0.5}
    >>> _ = (d / "summary.json").write_text(json.dumps({"wall_time": 10.0, "wall_time_by_phase": ph,
    ...     "launches": 1, "increments": 1, "dofs": 10, "driver_output_behind": 0.0, "remeshes": []}))
    >>> r = shares(d); r["wall"], r["solve"], round(r["outside"], 3)
    (10.0, 6.0, 0.4)
    >>> _ = (d / "summary.json").write_text(json.dumps({"wall_time": 10.5, "wall_time_by_phase": ph,
    ...     "launches": 1, "increments": 1, "dofs": 10, "remeshes": [{"remesh_seconds": 0.2, "transfer_seconds": 0.1}]}))
    >>> r = shares(d); r["startup"], r["remesh"], round(r["wall"], 2)
    (0.5, 0.30000000000000004, 9.8)
    """
    s = json.loads((root / "summary.json").read_text())
    ph = dict(s["wall_time_by_phase"])
    if "picture" in ph:
        picture = ph["picture"]
    else:                               # an older driver: the picture is inside driver_output
        png, pvd = root / "deformed.png", root / "results.pvd"
        picture = png.stat().st_mtime - pvd.stat().st_mtime if png.is_file() and pvd.is_file() else 0.0
        picture = min(max(picture, 0.0), ph["driver_output"])
        ph["driver_output"] -= picture
    if "remesh" not in ph:
        ph["remesh"] = sum(r.get("remesh_seconds", 0.0) + r.get("transfer_seconds", 0.0)
                           for r in s.get("remeshes") or [] if isinstance(r, dict))
    if "driver_output_behind" not in s:      # the launch wall time held the accept: out of the start-up
        ph["freefem_startup"] = max(ph["freefem_startup"] - ph["driver_output"], 0.0)
    solve = sum(ph[k] for k in SOLVE)
    wall = ph["mesh"] + ph["freefem_startup"] + solve + ph["freefem_output"] + ph["freefem_other"] \
        + ph["driver_output"] + ph.get("failed_launches", 0.0) + ph.get("failed_increments", 0.0) + ph["remesh"] \
        + picture
    row = {"dofs": s.get("dofs"), "increments": s["increments"], "launches": s["launches"], "wall": wall,
           "solve": solve, "startup": ph["freefem_startup"], "mesh": ph["mesh"],
           "freefem_output": ph["freefem_output"], "freefem_other": ph["freefem_other"],
           "driver_output": ph["driver_output"], "remesh": ph["remesh"], "picture": picture,
           "driver_output_behind": s.get("driver_output_behind", 0.0),
           "outside": 1.0 - solve / wall if wall else None}
    return row


GOAL_SOLVE, GOAL_LONG, GOAL_SMOKE = 5.0, 0.10, 0.30
"""Issue 20's goal: at most 10 % outside the solve for a solve above 5 s, at most 30 % for smoke-size runs."""


def goal(row: dict) -> str:
    """Whether a row meets issue 20's goal (outside share of the whole process), or that none applies.

    >>> goal({"size": "smoke", "solve": 0.1, "outside_process": 0.25}), goal({"size": "default", "solve": 9.0,
    ...     "outside_process": 0.4}), goal({"size": "default", "solve": 2.0, "outside_process": 0.4})
    ('≤30 %: yes', '≤10 %: no', '–')
    """
    share = row.get("outside_process")
    if not isinstance(share, float):
        return "–"
    if row.get("size") == "smoke":
        return f"≤30 %: {'yes' if share <= GOAL_SMOKE else 'no'}"
    if row.get("solve", 0.0) > GOAL_SOLVE:
        return f"≤10 %: {'yes' if share <= GOAL_LONG else 'no'}"
    return "–"


def bounds(row: dict) -> dict:
    """What the outside share would be with no process start to pay: ``without_startup`` with FreeFEM's
    start-up phase at zero (a FreeFEM that takes launch after launch), ``warm`` with the Python column at
    zero too (a process that imported the driver before the run, and such a FreeFEM). Lower bounds of those
    levers: neither would make the other phases shorter.

    >>> bounds({"process_wall": 10.0, "solve": 8.0, "startup": 0.5, "python": 0.5})
    {'without_startup': 0.1579, 'warm': 0.1111}
    """
    wall, solve = row["process_wall"], row["solve"]
    startup, python = row.get("startup", 0.0), row.get("python", 0.0)
    return {"without_startup": round(1.0 - solve / (wall - startup), 4),
            "warm": round(1.0 - solve / (wall - startup - python), 4)}


def same_fingerprints(a: Path, b: Path) -> bool:
    """Whether two runs of a scene agree: increments, Newton iterations, launches aside, DoFs, and every
    number of each increment's record to 1e-9 (not the clocks and the linear iterations: FreeFEM counts them
    from the start of its launch)."""
    sa, sb = (json.loads((r / "summary.json").read_text()) for r in (a, b))
    if any(sa[k] != sb[k] for k in ("increments", "newton_iterations", "dofs", "elements", "completed")):
        return False
    for ra, rb in zip(*(sorted((r / "fem").glob("inc-*/record.json")) for r in (a, b))):
        ja, jb = json.loads(ra.read_text()), json.loads(rb.read_text())
        for k, v in ja.items():
            if k.startswith("time_") or k == "linear_iterations" or not isinstance(v, (int, float)):
                continue
            if not isinstance(jb.get(k), (int, float)) or abs(v - jb[k]) > 1e-9 * max(abs(v), 1e-300):
                return False
    return True


@register("overhead")
def overhead(quick: bool, workdir: Path) -> list[dict]:
    """Every scene (smoke size with --quick, else default size or :data:`SCALE`): time outside the solve."""
    base = os.environ.get("WENDEL_BENCH_BASE")
    which = os.environ.get("WENDEL_BENCH_TREES", "both")      # base | this | both
    trees = ([Path(base).resolve()] if base and which != "this" else []) + ([None] if which != "base" else [])
    only = os.environ.get("WENDEL_BENCH_SCENES")       # e.g. "smoke,hertz": a subset
    for tree in trees:   # both trees' bytecode first: under PYTHONDONTWRITEBYTECODE=1 (this machine) a tree
        root = tree or THIS  # without it compiles its modules at every start (0.2-0.25 s, measured)
        subprocess.run([sys.executable, "-m", "compileall", "-q", str(root / "driver" / "wendel"), str(root / "meshes")],
                       capture_output=True)
    rows = []
    for scene in sorted(WORKFLOWS.glob("*.toml")):
        if only and scene.stem not in only.split(","):
            continue
        for tree in trees:
            out = workdir / scene.stem / ("base" if tree else "this")
            row = run_once(scene_for(tree, scene), out, quick, SCALE.get(scene.name), tree)
            if "process_wall" in row and "wall" in row:
                row["outside_process"] = 1.0 - row["solve"] / row["process_wall"]
                row["python"] = max(row["process_wall"] - row["wall"], 0.0)
                row["goal"] = goal(row)
                row.update(bounds(row))
            if tree is None and base and which == "both" and "wall" in row and "wall" in rows[-1]:
                row["same_as_base"] = same_fingerprints(workdir / scene.stem / "base", out)
            rows.append(row)
            more = f" (no FreeFEM start {row['without_startup']:.0%}, warm {row['warm']:.0%})" if "warm" in row else ""
            more += f", CPU {row['cpu']:.2f} s" if "cpu" in row else ""
            print(f"  {row['scene']} ({row['tree']}): {row['process_wall']:.2f} s, outside "
                  f"{row.get('outside_process', float('nan')):.0%}{more} {row.get('error', '')}", flush=True)
    return rows


PHASES = [("startup", "start-up"), ("mesh", "meshing"), ("freefem_output", "FreeFEM output"),
          ("freefem_other", "FreeFEM set-up"), ("driver_output", "driver output"), ("remesh", "remesh"),
          ("picture", "picture"), ("python", "Python")]
"""The columns of the table: each phase as a share of the whole process (Python: its start, imports,
provenance, checkpoints; the process wall time minus the run's phases)."""


def side_by_side(before: list[dict], after: list[dict]) -> str:
    """A Markdown table of two benchmark runs' rows (``before → after`` per column), scene by scene; phases
    as shares of the whole process, the outside share and whether it meets the goal (:func:`goal`).

    >>> r = {"scene": "s", "size": "smoke", "launches": 2, "process_wall": 2.0, "wall": 1.0, "solve": 0.5,
    ...      "outside_process": 0.75, "startup": 0.2, "mesh": 0.1, "freefem_output": 0.1, "freefem_other": 0.1,
    ...      "driver_output": 0.05, "remesh": 0.0, "picture": 0.05, "python": 1.0, "goal": "≤30 %: no"}
    >>> side_by_side([r], [dict(r, launches=1, same_as_base=True)]).splitlines()[2]
    '| s | smoke | 2 → 1 | 2.0 → 2.0 | 0.50 → 0.50 | **75% → 75%** | 10% → 10% | 5% → 5% | 5% → 5% | 5% → 5% | 2% → 2% | 0% → 0% | 2% → 2% | 50% → 50% | ≤30 %: no → ≤30 %: no | yes |'
    """
    cols = [("launches", "launches"), ("process_wall", "process (s)"), ("solve", "solve (s)"),
            ("outside_process", "outside the solve")] + PHASES + [("goal", "goal met")]
    lines = ["| scene | size | " + " | ".join(c[1] for c in cols) + " | same fingerprints |",
             "|---|---|" + "---|" * (len(cols) + 1)]
    old = {(r["scene"], r["size"]): r for r in before}

    def fmt(x: dict, k: str) -> str:
        v = x.get(k)
        if k == "goal":
            return v or "–"
        if not isinstance(v, (int, float)) or isinstance(v, bool):
            return "–"
        if k == "launches":
            return f"{v:d}"
        if k == "process_wall":
            return f"{v:.1f}"
        if k == "solve":
            return f"{v:.2f}"
        if k == "outside_process":
            return f"{v:.0%}"
        return f"{v / x['process_wall']:.0%}" if x.get("process_wall") else "–"

    for r in after:
        b = old.get((r["scene"], r["size"]), {})
        cells = []
        for k, _ in cols:
            c = f"{fmt(b, k)} → {fmt(r, k)}"
            cells.append(f"**{c}**" if k == "outside_process" else c)
        same = {True: "yes", False: "NO"}.get(r.get("same_as_base"), "–")
        lines.append(f"| {r['scene']} | {r['size']} | " + " | ".join(cells) + f" | {same} |")
    return "\n".join(lines)


def pairs(rows: list[dict]) -> tuple[list[dict], list[dict]]:
    """The base and this tree's rows of benchmark runs (one run with WENDEL_BENCH_BASE holds both)."""
    return [r for r in rows if r.get("tree") == "base"], [r for r in rows if r.get("tree") != "base"]


if __name__ == "__main__":      # python -m wendel.bench.overhead RUN.json ... (rows of both trees)
    import sys as _sys

    rows = [r for p in _sys.argv[1:] for r in json.loads(Path(p).read_text())["rows"]]
    print(side_by_side(*pairs(rows)))
