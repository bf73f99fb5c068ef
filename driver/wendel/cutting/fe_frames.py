"""One PNG frame of an FE cut: the deformed workpiece near the tool, coloured by the equivalent plastic
strain, with the tool (its rounded edge drawn as arcs) at its place on the path."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def rounded_outline(vertices, radii, per_arc: int = 16) -> np.ndarray:
    """The outline of a polygon whose corners are rounded by ``radii`` (the tool of ``edp/lib/tool.idp``),
    ``per_arc`` points on each arc (:func:`wendel.remesh.snap.outline`)."""
    from ..remesh.snap import outline

    return outline(vertices, radii, per_arc)


def frame(path: Path, points, cells, p_cells, tool: dict, shift, title: str, h: float) -> Path:
    """Write the frame ``path`` (positions in mm; ``p_cells`` the cells' equivalent plastic strain or None)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation

    path.parent.mkdir(parents=True, exist_ok=True)
    tip = np.array(tool["tip"]) + shift
    fig, ax = plt.subplots(figsize=(7, 5))
    tri = Triangulation(points[:, 0], points[:, 1], cells)
    if p_cells is not None:
        pc = ax.tripcolor(tri, facecolors=np.asarray(p_cells).ravel(), cmap="viridis", vmin=0,
                          vmax=max(float(np.max(p_cells)), 1e-6))
        fig.colorbar(pc, ax=ax, label="equivalent plastic strain")
    ax.triplot(tri, lw=0.2, color="k", alpha=0.4)
    outline = rounded_outline(tool["vertices"], tool["radii"]) + shift
    ax.fill(*outline.T, color="#7a7a7a", alpha=0.85)
    ax.set_xlim(tip[0] - 5 * h, tip[0] + 3 * h)
    ax.set_ylim(tip[1] - 2.5 * h, tip[1] + 4 * h)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title(title, fontsize=8)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path
