"""Error against run time over a sequence of refined meshes (``wendel study SCENE --levels K``).

Level k runs the scene with element size h / 2^k (and the size of a refined zone, ``geometry.refine.h``,
scaled alike). The error is against the scene's analytic
reference (relative L2 and H1 norms computed by FreeFEM with a high-order quadrature) when it
declares one, else against the finest run's ``reference.quantity``. Writes study.csv and
error_vs_runtime.png (log-log, observed convergence rates in the legend). A scene whose reference names
another code's figures (``reference.compare``) also gets ``<quantity>_vs_runtime.png``: the quantity of
every level against its wall time next to those figures.
"""

from __future__ import annotations

import csv
import json
import math
import time
from pathlib import Path

from .comparisons import COMPARISONS
from .comparisons import plot as plot_quantity
from ..loop import RESULTS, run
from ..scene import load


def rates(h: list[float], err: list[float]) -> list[float | None]:
    """Observed rates log(e_k-1/e_k)/log(h_k-1/h_k) between successive levels.

    >>> [round(r, 6) for r in rates([1, 0.5, 0.25], [1, 0.25, 0.0625])[1:]]
    [2.0, 2.0]
    """
    out: list[float | None] = [None]
    for k in range(1, len(h)):
        if err[k] > 0 and err[k - 1] > 0 and h[k] != h[k - 1]:
            out.append(math.log(err[k - 1] / err[k]) / math.log(h[k - 1] / h[k]))
        else:
            out.append(None)
    return out


def study(scene_path: str | Path, levels: int = 3, smoke: bool = False, ranks: int | None = None,
          out: Path | None = None, progress=print) -> Path:
    """Run ``levels`` refinements of the scene and write the error-against-run-time study."""
    if levels < 2:
        raise ValueError("--levels must be at least 2")
    scene_path = Path(scene_path)
    scene = load(scene_path, smoke=smoke)
    root = Path(out).resolve() if out else RESULTS / scene_path.stem / ("study-" + time.strftime("%Y%m%d-%H%M%S"))
    root.mkdir(parents=True, exist_ok=True)
    rows = []
    for k in range(levels):
        h = scene.geometry.h / 2 ** k
        progress(f"study level {k + 1}/{levels}: h = {h:g}")
        run_dir = run(scene_path, smoke=smoke, ranks=ranks, out=root / f"level-{k}", scale=0.5 ** k, png=False,
                      progress=lambda *_: None)
        s = json.loads((run_dir / "summary.json").read_text())
        last = s["last_increment"]
        rows.append({"level": k, "h": h, "h_max": last["h_max"], "dofs": s["dofs"], "wall_time": s["wall_time"],
                     "solve_time": s["wall_time_by_phase"]["assembly"] + s["wall_time_by_phase"]["linear_solve"]
                     + s["wall_time_by_phase"]["constitutive"],
                     "newton_iterations": s["newton_iterations"], "last": last})
    all_rows = list(rows)
    comparison = COMPARISONS[scene.reference.compare] if scene.reference.compare is not None else None
    for r in rows:                     # the reference quantity (study.csv) and the compared one (picture)
        for key in {scene.reference.quantity} | ({comparison.quantity} if comparison else set()):
            if key in r["last"]:
                r[key] = r["last"][key]
    analytic = scene.reference.analytic is not None or bool(scene.reference.errors)
    names = []
    if scene.reference.analytic is not None:
        for r in rows:
            r["error_l2"] = r["last"]["error_l2"] / r["last"]["reference_l2"]
            r["error_h1"] = r["last"]["error_h1"] / r["last"]["reference_h1"]
        names = ["error_l2", "error_h1"]
    if scene.reference.errors:
        names += list(scene.reference.errors)
        for r in rows:
            for name in names:
                if name not in r["last"]:
                    raise KeyError(f"reference.errors: {name!r} is not in record.json of level {r['level']}")
                ref = r["last"].get("reference_" + name.removeprefix("error_"))
                r[name] = abs(r["last"][name]) / ref if ref else abs(r["last"][name])   # relative when possible
    if not analytic:
        q = scene.reference.quantity
        ref = rows[-1]["last"].get(q)
        if ref is None:
            raise KeyError(f"reference.quantity {q!r} is not in record.json; valid: "
                           f"{', '.join(k for k, v in rows[-1]['last'].items() if isinstance(v, (int, float)))}")
        for r in rows:
            r[f"error_{q}"] = abs(r["last"][q] - ref) / abs(ref) if ref else abs(r["last"][q] - ref)
        rows = rows[:-1]          # the finest run is the reference: no error of its own
        names = [f"error_{q}"]
    q = scene.reference.quantity
    hs = [r["h"] for r in rows]
    for name in names:
        for r, rate in zip(rows, rates(hs, [r[name] for r in rows])):
            r[f"rate_{name.removeprefix('error_')}"] = rate
    cols = ["level", "h", "h_max", "dofs", "newton_iterations", "wall_time", "solve_time"] + \
        ([q] if q in rows[0] else []) + [c for c in rows[0] if c.startswith(("error_", "rate_"))]
    with open(root / "study.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    plot(root / "error_vs_runtime.png", rows, names, scene_path.stem,
         "closed-form reference" if analytic else f"finest run ({levels - 1} levels shown)")
    if comparison is not None:
        levels_q = [r for r in all_rows if comparison.quantity in r]
        plot_quantity(root / f"{comparison.quantity}_vs_runtime.png", levels_q, comparison.quantity,
                      scene_path.stem, comparison)
    return root


def plot(png: Path, rows: list[dict], names: list[str], title: str, against: str) -> None:
    """Log-log error against wall time, with the observed rate in h of the last pair in the legend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    for name in names:
        t = [r["wall_time"] for r in rows]
        e = [r[name] for r in rows]
        rate = rows[-1].get(f"rate_{name.removeprefix('error_')}")
        label = name.removeprefix("error_") + (f" (rate in h: {rate:.2f})" if rate is not None else "")
        ax.loglog(t, e, "o-", label=label)
        for r in rows:
            ax.annotate(f"{r['dofs']} DoFs", (r["wall_time"], r[name]), fontsize=7, xytext=(4, 4),
                        textcoords="offset points")
    ax.set_xlabel("wall time of the run [s]")
    ax.set_ylabel("relative error")
    ax.set_title(f"{title}: error against {against}")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)
