"""The table of a sweep, collected from its run folders: sweep.csv and PNG plots.

One row per planned run: its parameters, status (done, failed, interrupted, pending), the message of a
failure, the wall time of ``wendel run`` as the sweep measured it (``run_wall``, all attempts), and the
fingerprints of summary.json (DoFs, increments, Newton iterations, wall time, errors, the numbers of the
last increment). Plots: each chosen output against each parameter (``<output>.png``), a heat map per
output when the sweep is a two-parameter grid (``heatmap-<output>.png``), and the error against run time
(log-log, summary.json wall time, coarse to fine) when the sweep is over ``geometry.h``; time it with
``--workers 1``, as concurrent runs slow each other. Plots are redrawn only when sweep.csv changed.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path

from .folders import read_json, run_dir, state

SUMMARY_KEYS = ("dofs", "elements", "ranks", "increments", "newton_iterations", "step_cuts", "launches", "wall_time")


def row(root: Path, entry: dict) -> dict:
    """The table row of one planned run (``entry`` from plan.json)."""
    folder = run_dir(root, entry["key"])
    status, message = state(folder)
    r = {"key": entry["key"], **entry["params"], "status": status, "message": message}
    rec = read_json(folder / "sweep.json") or {}
    r["run_wall"] = rec.get("wall")
    summary = read_json(folder / "summary.json") or {}
    for k in SUMMARY_KEYS:
        r[k] = summary.get(k)
    for k, v in (summary.get("errors") or {}).items():
        r[k] = v
    for k, v in (summary.get("outputs") or {}).items():      # a run's own scalar outputs (drilling: probes, bore)
        r[k] = v
    for k, v in (summary.get("last_increment") or {}).items():
        if (isinstance(v, (int, float)) and not isinstance(v, bool) and k not in r
                and not k.startswith(("time_", "error_", "reference_"))):     # errors: from summary["errors"]
            r[k] = v
    return r


def collect(root: Path, plan: dict) -> tuple[list[dict], Path, bool]:
    """Write sweep.csv from the folders; return (rows, csv path, whether it changed)."""
    rows = [row(root, e) for e in plan["runs"]]
    keys = list(dict.fromkeys(k for r in rows for k in r))
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=keys, lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    path = root / "sweep.csv"
    changed = not path.is_file() or path.read_text() != buf.getvalue()
    if changed:
        path.write_text(buf.getvalue())
    return rows, path, changed


def _num(v) -> float | None:
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) else None


def plots(root: Path, plan: dict, rows: list[dict], force: bool = False) -> list[Path]:
    """Draw the plots of the sweep into ``root``; return their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    params, outputs = plan["parameters"], plan["outputs"]
    done = [r for r in rows if r["status"] == "done"]
    written = []
    for out in outputs:
        vals = [(r, _num(r.get(out))) for r in done]
        vals = [(r, v) for r, v in vals if v is not None]
        if not vals:
            continue
        fig, axes = plt.subplots(1, len(params), figsize=(4 * len(params), 3.4), squeeze=False)
        for ax, p in zip(axes[0], params):
            xs = [(_num(r.get(p)), v) for r, v in vals if _num(r.get(p)) is not None]
            xs.sort()
            ax.plot([x for x, _ in xs], [v for _, v in xs], "o")
            ax.set_xlabel(p)
            ax.set_ylabel(out)
            ax.grid(alpha=0.3)
        fig.tight_layout()
        path = root / f"{_safe(out)}.png"
        fig.savefig(path, dpi=90)
        plt.close(fig)
        written.append(path)
        if plan.get("grid2"):
            written += [_heatmap(root, plan["grid2"], out, vals, plt)]
    if "geometry.h" in params:
        p = _error_vs_runtime(root, [dict(r) for r in done], plt, params, plan.get("reference_quantity"))
        if p:
            written.append(p)
    return written


def _short(v) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "._-" else "-" for c in name)


def _heatmap(root: Path, grid: dict, out: str, vals, plt) -> Path:
    (kx, xs), (ky, ys) = list(grid.items())
    import numpy as np

    z = np.full((len(ys), len(xs)), np.nan)
    for r, v in vals:
        if r.get(kx) in xs and r.get(ky) in ys:
            z[ys.index(r[ky]), xs.index(r[kx])] = v
    fig, ax = plt.subplots(figsize=(5, 4))
    im = ax.imshow(z, origin="lower", aspect="auto", cmap="viridis")
    ax.set_xticks(range(len(xs)), [f"{x:g}" if isinstance(x, (int, float)) else str(x) for x in xs])
    ax.set_yticks(range(len(ys)), [f"{y:g}" if isinstance(y, (int, float)) else str(y) for y in ys])
    ax.set_xlabel(kx)
    ax.set_ylabel(ky)
    for i in range(len(ys)):
        for j in range(len(xs)):
            if not np.isnan(z[i, j]):
                ax.text(j, i, f"{z[i, j]:.3g}", ha="center", va="center", color="w", fontsize=8)
    fig.colorbar(im, ax=ax, label=out)
    fig.tight_layout()
    path = root / f"heatmap-{_safe(out)}.png"
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def _error_vs_runtime(root: Path, done: list[dict], plt, params: list[str], quantity: str | None) -> Path | None:
    """Error against run time over mesh sizes (log-log): each error column of the table; without one, the
    difference of the scene's reference quantity to the finest run with the same other parameters."""
    names = [k for k in dict.fromkeys(k for r in done for k in r) if k.startswith("error_")]
    names = [n for n in names if n.endswith("_relative")] or names
    if not names and quantity:
        others = [p for p in params if p != "geometry.h"]
        groups: dict[tuple, list[dict]] = {}
        for r in done:
            if _num(r.get(quantity)) is not None:
                groups.setdefault(tuple(r.get(p) for p in others), []).append(r)
        for g in groups.values():
            ref = _num(min(g, key=lambda r: r["geometry.h"])[quantity])
            for r in g:
                r[f"difference_{quantity}"] = abs(_num(r[quantity]) - ref) / abs(ref) if ref else None
        names = [f"difference_{quantity}"]
    if not names:
        return None
    fig, ax = plt.subplots(figsize=(5, 4))
    others = [p for p in params if p != "geometry.h"]
    groups: dict[tuple, list[dict]] = {}
    for r in done:
        groups.setdefault(tuple(r.get(p) for p in others), []).append(r)
    for n in names:
        for g, rows in groups.items():
            pts = [(_num(r.get("wall_time")) or _num(r.get("run_wall")), _num(r.get(n)))
                   for r in sorted(rows, key=lambda r: -r["geometry.h"])                 # coarse to fine
                   if _num(r.get(n)) and (_num(r.get("wall_time")) or _num(r.get("run_wall")))]
            label = n + "".join(f", {p.rsplit('.', 1)[-1]}={_short(v)}" for p, v in zip(others, g))
            if pts:
                ax.loglog([t for t, _ in pts], [e for _, e in pts], "o-", label=label)
    ax.set_xlabel("run wall time (summary.json) [s]")
    ax.set_ylabel("relative error" if not names[0].startswith("difference_")
                  else f"{quantity}: relative difference to the finest h")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    fig.tight_layout()
    path = root / "error_vs_runtime.png"
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
