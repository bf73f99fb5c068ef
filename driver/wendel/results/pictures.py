"""Pictures of a result: the deformed body, off-screen with pyvista (``deformed.png`` of a run)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np


def picture(vtu: Path, png: Path, title: str, warp: float = 0.0, field: str | None = None) -> None:
    """Render the deformed body off-screen, coloured by ``field`` (von Mises by default)."""
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

    pv.OFF_SCREEN = True
    grid = pv.read(vtu)
    if "u" in grid.point_data and np.ndim(grid.point_data["u"]) == 1:
        # a scalar field on a plane (membrane, torsion): show it as a surface z = u
        u = np.asarray(grid.point_data["u"])
        size = max(np.ptp(np.asarray(grid.points), axis=0))
        scale = warp or (0.3 * size / (float(np.abs(u).max()) or 1.0))
        grid = grid.warp_by_scalar("u", factor=scale, normal=(0, 0, 1))
        field = field or "u"
        title = f"{title} (u x{scale:.3g} upwards)"
    elif "u" in grid.point_data:
        u = grid.point_data["u"]
        size = max(np.ptp(grid.points, axis=0))
        umax = float(np.abs(u).max()) or 1.0
        # true scale for visible deformations and remeshed bodies (their mesh is already the deformed
        # body), magnified to 10% of the size for small ones
        large = umax >= 0.05 * size or "u_total" in grid.point_data
        scale = warp or (1.0 if large else 0.1 * size / umax)
        grid = grid.warp_by_vector("u", factor=scale)
        title = f"{title} (displacement x{scale:.3g})"
    field = field or ("vonMises" if "vonMises" in grid.cell_data else None)
    plotter = pv.Plotter(off_screen=True, window_size=(900, 700))
    plotter.add_mesh(grid, scalars=field, show_edges=grid.n_cells < 20000, cmap="viridis",
                     scalar_bar_args={"title": field or ""})
    plotter.add_text(title, font_size=10)
    if np.ptp(np.asarray(grid.points)[:, 2]) == 0:
        plotter.view_xy()
    else:
        plotter.view_isometric()
    plotter.screenshot(png)
    plotter.close()
