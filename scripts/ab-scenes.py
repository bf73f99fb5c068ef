#!/usr/bin/env python3
"""A change against the checkout before it, scene by scene: interleaved runs and the largest difference.

Usage (under the heavy lock on a shared machine)::

    .venv/bin/python scripts/ab-scenes.py BASE_CHECKOUT OUT_DIR ROUNDS SCENE [SCENE ...]

BASE_CHECKOUT is another checkout of wendel whose ``build/`` holds the plugins (a symbolic link to this tree's
``build/`` serves when the change leaves the plugins alone); it runs with this tree's Python and its own driver,
.edp files and meshes. Each round runs every scene at its default size with the base, then with this tree, and
prints the run's wall time and its assembly, linear solve and constitutive update (summary.json). At the end,
for every scene, the first round's two histories (history.csv) are compared column by column: the largest
difference over the increments relative to the column's largest magnitude over the run (so that a quantity
that is zero up to round-off, such as the heat through an insulated face, is not read as a relative change),
clocks, residuals and linear iterations aside (the three largest, each with its column's magnitude: a column that
is round-off over the whole run shows as a large relative difference of a tiny magnitude), and whether the
Newton counts are the same. ROUNDS = 0 only compares the runs already in OUT_DIR.
"""
from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

THIS = Path(__file__).resolve().parents[1]
SKIP = ("residual", "relative_residual", "thermal_residual", "energy_balance_error", "linear_iterations")


def run(tree: Path | None, scene: str, out: Path) -> dict:
    """One run of workflows/SCENE.toml with the driver of ``tree`` (None: this tree); its summary."""
    env = dict(os.environ)
    if tree is not None:
        env["PYTHONPATH"] = str(tree / "driver")
    code = "from wendel.cli import entry; entry()"
    with open(f"{out}.log", "w") as log:
        subprocess.run([sys.executable, "-c", code, "run", str(THIS / "workflows" / f"{scene}.toml"), "--out", str(out)],
                       env=env, stdout=log, stderr=subprocess.STDOUT, check=True)
    return json.loads((out / "summary.json").read_text())


def largest_differences(a: Path, b: Path, n: int = 3) -> tuple[list[tuple[float, str, float]], bool]:
    """The n largest differences between two runs' histories, each relative to its column's largest magnitude
    over both runs, with that magnitude (see the module's text); whether the Newton counts agree."""
    ha, hb = (list(csv.DictReader(open(r / "history.csv"))) for r in (a, b))
    if len(ha) != len(hb):
        return [(float("inf"), f"{len(ha)} against {len(hb)} increments", 0.0)], False
    rows = []
    for k in ha[0]:
        if k.startswith("time") or k in SKIP:
            continue
        try:
            xs, ys = [float(r[k]) for r in ha], [float(r[k]) for r in hb]
        except (ValueError, KeyError):
            continue
        scale = max(max(abs(x) for x in xs + ys), 1e-300)
        rows.append((max(abs(x - y) for x, y in zip(xs, ys)) / scale, k, scale))
    return sorted(rows, reverse=True)[:n], [r["newton_iterations"] for r in ha] == [r["newton_iterations"] for r in hb]


def main(argv: list[str]) -> None:
    base, out, rounds, scenes = Path(argv[0]).resolve(), Path(argv[1]).resolve(), int(argv[2]), argv[3:]
    out.mkdir(parents=True, exist_ok=True)
    for r in range(1, rounds + 1):         # ROUNDS = 0: compare the runs already in OUT_DIR
        for scene in scenes:
            for name, tree in (("base", base), ("this", None)):
                d = out / f"{scene}-{name}-{r}"
                shutil.rmtree(d, ignore_errors=True)
                s = run(tree, scene, d)
                p = s["wall_time_by_phase"]
                print(f"{scene} {name} round {r}: wall {s['wall_time']:.2f} s, assembly {p['assembly']:.2f} s, "
                      f"linear solve {p['linear_solve']:.2f} s, constitutive {p['constitutive']:.2f} s, "
                      f"{s['newton_iterations']} Newton, load {os.getloadavg()[0]:.1f}", flush=True)
    for scene in scenes:
        worst, same = largest_differences(out / f"{scene}-base-1", out / f"{scene}-this-1")
        text = ", ".join(f"{k} {d:.1e} (magnitude {m:.1e})" for d, k, m in worst)
        print(f"{scene}: same Newton counts: {same}; largest differences relative to the column's magnitude: {text}")

if __name__ == "__main__":
    main(sys.argv[1:])
