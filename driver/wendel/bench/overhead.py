"""Benchmark ``overhead`` (issue 20): every second outside the solve, scene by scene.

Each scene of workflows/ is run as its own ``python`` process (so Python's start-up and imports count), and
the shares of its wall time are read from the run's summary.json: FreeFEM start-up (launch wall time minus
FreeFEM's clock), meshing (gmsh), FreeFEM file output, driver output (VTU, histories), picture (the wait for the PNG) and
the rest of the process (Python start-up, imports, provenance). "solve" is assembly + linear solve + constitutive
update; ``outside`` is the share of everything else in the run's wall time (the sum of summary.json's phases),
``outside_process`` the same share of the whole process.

``--quick``: every scene at its smoke size. Otherwise each scene at its default size, except those of
:data:`SCALE` (their default takes minutes on the shared 2-core machine): geometry.h multiplied as stated.

Before/after side by side: ``WENDEL_BENCH_BASE=/path/to/an/older/checkout wendel bench overhead`` runs each
scene with that checkout's driver too (same Python, alternating, one run each); the rows say which
(``tree``: ``base`` or ``this``) and ``same_as_base`` says whether both gave the same fingerprints
(:func:`same_fingerprints`). An older checkout's summary.json has no ``picture`` phase: its picture time
is read from the run folder (``deformed.png`` written minus ``results.pvd`` written) and taken out of its
driver output.
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

_CHILD = """
import sys
from pathlib import Path
tree, scene, out, smoke, scale = sys.argv[1:6]
if tree:
    sys.path.insert(0, str(Path(tree) / "driver"))
from wendel.loop import run
run(scene, smoke=smoke == "1", out=Path(out), progress=lambda *a: None,
    scale=float(scale) if scale else None)
"""


def run_once(scene: Path, out: Path, smoke: bool, scale: float | None, tree: Path | None = None) -> dict:
    """Run ``scene`` in a fresh Python process (the driver of checkout ``tree``, or this one); its row."""
    shutil.rmtree(out, ignore_errors=True)
    cmd = [sys.executable, "-c", _CHILD, str(tree or ""), str(scene), str(out), "1" if smoke else "0",
           "" if scale is None or smoke else repr(scale)]
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=tree or WORKFLOWS.parent)
    process = time.perf_counter() - t0
    row = {"scene": scene.stem, "size": "smoke" if smoke else (f"h x{scale:g}" if scale else "default"),
           "tree": "base" if tree else "this", "load_average": round(load, 1), "process_wall": process}
    if proc.returncode != 0 or not (out / "summary.json").is_file():
        row["error"] = (proc.stderr.strip().splitlines() or ["?"])[-1][:200]
        return row
    return {**row, **shares(out)}


def shares(root: Path) -> dict:
    """The phases of the run in ``root`` in seconds and as shares of its wall time.

    >>> import tempfile; d = Path(tempfile.mkdtemp())
    >>> ph = {"mesh": 1.0, "freefem_startup": 1.0, "assembly": 2.0, "linear_solve": 4.0, "constitutive": 0.0,
    ...       "freefem_output": 0.5, "freefem_other": 0.5, "driver_output": 0.5, "picture": 0.5}
    >>> _ = (d / "summary.json").write_text(json.dumps({"wall_time": 10.0, "wall_time_by_phase": ph,
    ...                                                  "launches": 1, "increments": 1, "dofs": 10}))
    >>> r = shares(d); r["wall"], r["solve"], round(r["outside"], 3)
    (10.0, 6.0, 0.4)
    """
    s = json.loads((root / "summary.json").read_text())
    ph = dict(s["wall_time_by_phase"])
    wall = s["wall_time"]
    if "picture" in ph:
        picture = ph["picture"]
    else:                               # an older driver: the picture is inside driver_output
        png, pvd = root / "deformed.png", root / "results.pvd"
        picture = png.stat().st_mtime - pvd.stat().st_mtime if png.is_file() and pvd.is_file() else 0.0
        picture = min(max(picture, 0.0), ph["driver_output"])
        ph["driver_output"] -= picture
    solve = sum(ph[k] for k in SOLVE)
    row = {"dofs": s.get("dofs"), "increments": s["increments"], "launches": s["launches"], "wall": wall,
           "solve": solve, "startup": ph["freefem_startup"], "mesh": ph["mesh"],
           "freefem_output": ph["freefem_output"], "freefem_other": ph["freefem_other"],
           "driver_output": ph["driver_output"], "picture": picture,
           "outside": 1.0 - solve / wall if wall else None}
    return row


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
    rows = []
    for scene in sorted(WORKFLOWS.glob("*.toml")):
        if only and scene.stem not in only.split(","):
            continue
        for tree in trees:
            out = workdir / scene.stem / ("base" if tree else "this")
            row = run_once(scene, out, quick, SCALE.get(scene.name), tree)
            if "process_wall" in row and "wall" in row:
                row["outside_process"] = 1.0 - row["solve"] / row["process_wall"]
            if tree is None and base and which == "both" and "wall" in row and "wall" in rows[-1]:
                row["same_as_base"] = same_fingerprints(workdir / scene.stem / "base", out)
            rows.append(row)
            print(f"  {row['scene']} ({row['tree']}): {row['process_wall']:.2f} s, outside "
                  f"{row.get('outside', float('nan')):.0%} {row.get('error', '')}", flush=True)
    return rows


def side_by_side(before: list[dict], after: list[dict]) -> str:
    """A Markdown table of two benchmark runs' rows (``before -> after`` per column), scene by scene.

    >>> r = {"scene": "s", "size": "smoke", "launches": 2, "process_wall": 2.0, "wall": 1.0, "solve": 0.5,
    ...      "outside": 0.5, "startup": 0.2, "mesh": 0.1, "freefem_output": 0.1, "driver_output": 0.05,
    ...      "picture": 0.05}
    >>> side_by_side([r], [dict(r, launches=1)]).splitlines()[2]
    '| s | smoke | 2 → 1 | 2.0 → 2.0 | 1.0 → 1.0 | 0.50 → 0.50 | 50% → 50% | 0.20 → 0.20 | 0.10 → 0.10 | 0.10 → 0.10 | 0.05 → 0.05 | 0.05 → 0.05 |'
    """
    cols = [("launches", "launches", "{:d}"), ("process_wall", "process (s)", "{:.1f}"), ("wall", "run (s)", "{:.1f}"),
            ("solve", "solve (s)", "{:.2f}"), ("outside", "outside solve", "{:.0%}"),
            ("startup", "FreeFEM start-up (s)", "{:.2f}"), ("mesh", "meshing (s)", "{:.2f}"),
            ("freefem_output", "FreeFEM output (s)", "{:.2f}"), ("driver_output", "driver output (s)", "{:.2f}"),
            ("picture", "picture (s)", "{:.2f}")]
    lines = ["| scene | size | " + " | ".join(c[1] for c in cols) + " |", "|---|---|" + "---|" * len(cols)]
    old = {(r["scene"], r["size"]): r for r in before}
    for r in after:
        b = old.get((r["scene"], r["size"]), {})
        cell = lambda k, f: " → ".join(f.format(x[k]) if isinstance(x.get(k), (int, float)) else "–" for x in (b, r))
        lines.append(f"| {r['scene']} | {r['size']} | " + " | ".join(cell(k, f) for k, _, f in cols) + " |")
    return "\n".join(lines)


if __name__ == "__main__":      # python -m wendel.bench.overhead BEFORE.json AFTER.json
    import sys as _sys

    rows = [json.loads(Path(p).read_text())["rows"] for p in _sys.argv[1:3]]
    print(side_by_side(*rows))
