"""Figures of other codes that a study plots next to its own runs (``reference.compare`` of a scene).

Each entry is a quantity of record.json measured by another code on this machine, at several meshes, with
the wall time it took. ``wendel study`` draws the scene's mesh sequence (quantity against wall time) and
these points in one picture, ``<quantity>_vs_runtime.png``.

>>> sorted(COMPARISONS)
['dealii-step42-ball', 'dealii-step42-stamp']
>>> COMPARISONS["dealii-step42-ball"].quantity
'contact_force'
"""

from __future__ import annotations

import dataclasses

# deal.II 9.4.1 step-42 (Q1, 1 MPI rank) measured on this machine (`wendel bench step42-dealii` measures it
# again): (case, DoFs, Newton steps, contact nodes, contact force, wall time s).
DEALII_REFERENCE = [
    ("global 4", 14739, 7, 9, 62.31, 3.4),
    ("global 5", 107811, 9, 37, 59.10, 64.0),
    ("adaptive cycle 3", 52497, 10, 145, 56.79, 82.0),
    ("adaptive cycle 4", 154647, 19, 585, 55.84, 398.0),
]
DEALII_STAMP_REFERENCE = ("stamp, global 4", 14739, 5, None, 123.6, 2.5)
FINE_FORCE = 55.0        # step-42's force on meshes finer than adaptive cycle 4 (still converging)


@dataclasses.dataclass(frozen=True)
class Comparison:
    """Another code's values of one quantity: points (label, DoFs, value, wall time s) and a target band."""

    quantity: str
    source: str
    points: tuple
    target: float | None = None        # the converged value, if known
    band: float = 0.02                 # relative half-width of the band drawn around it


COMPARISONS = {
    "dealii-step42-ball": Comparison(
        "contact_force", "deal.II 9.4.1 step-42, Q1, 1 rank, this machine",
        tuple((c, n, f, t) for c, n, _, _, f, t in DEALII_REFERENCE), FINE_FORCE),
    "dealii-step42-stamp": Comparison(
        "contact_force", "deal.II 9.4.1 step-42, Q1, 1 rank, this machine",
        ((DEALII_STAMP_REFERENCE[0], DEALII_STAMP_REFERENCE[1], DEALII_STAMP_REFERENCE[4],
          DEALII_STAMP_REFERENCE[5]),)),
}


def plot(png, rows: list[dict], quantity: str, title: str, comparison: Comparison | None) -> None:
    """The quantity of each study level against its wall time (labels: DoFs), with the other code's points."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.8, 4.8))
    t = [r["wall_time"] for r in rows]
    v = [r[quantity] for r in rows]
    ax.plot(t, v, "s-", label="wendel (this study)")
    for r in rows:
        ax.annotate(f"{r['dofs']:,}", (r["wall_time"], r[quantity]), fontsize=7, xytext=(4, 4),
                    textcoords="offset points")
    if comparison is not None:
        ax.plot([p[3] for p in comparison.points], [p[2] for p in comparison.points], "kv", linestyle="none", label=comparison.source)
        for label, dofs, value, wall in comparison.points:
            ax.annotate(f"{label}: {dofs:,}", (wall, value), fontsize=7, xytext=(4, -10), textcoords="offset points")
        if comparison.target is not None:
            ax.axhspan(comparison.target * (1 - comparison.band), comparison.target * (1 + comparison.band),
                       color="green", alpha=0.12, label=f"within {comparison.band:.0%} of {comparison.target:g}")
    ax.set_xscale("log")
    ax.set_xlabel("wall time of the run [s] (labels: DoFs)")
    ax.set_ylabel(quantity)
    ax.set_title(f"{title}: {quantity} against run time")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)
