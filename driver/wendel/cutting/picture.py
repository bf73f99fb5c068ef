"""A picture of the Oxley solution: workpiece, tool polygon, shear plane, chip and contact length, to scale.

The tool's tip is at the origin and the tool moves in -x; the shear plane runs from the tip at the shear
angle phi up to the free surface, the chip (thickness t2) flows up the rake face, the tool-chip contact
is drawn over its length. The same geometry conventions as :mod:`wendel.cutting.tool`.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .oxley import Result
from .tool import ToolPolygon


def oxley_picture(result: Result, tool: ToolPolygon, path: Path, title: str = "") -> Path:
    """Draw ``result`` with ``tool`` (tip at the origin) into the PNG ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t1, t2, a, phi = result.uncut, result.chip_thickness, result.rake, result.phi
    up = np.array([math.sin(a), math.cos(a)])                 # along the rake face
    p = np.array([-t1 / math.tan(phi), t1])                    # top of the shear plane
    span = max(6 * t1, 1.5 * abs(p[0]))
    chip_length = 3.5 * t2
    work = np.array([[-span, -2 * t1], [3 * t1, -2 * t1], [3 * t1, 0.0], [0.0, 0.0], p, [-span, t1]])
    chip = np.array([[0.0, 0.0], p, p + chip_length * up, chip_length * up])
    mm = 1e3
    fig, ax = plt.subplots(figsize=(9, 6))
    ax.fill(*(work * mm).T, color="#c9d6e3", label="workpiece")
    ax.fill(*(chip * mm).T, color="#f2b880", label=f"chip, t2 = {t2 * mm:.3f} mm")
    ax.fill(*(tool.vertices * mm).T, color="#7a7a7a", alpha=0.9, label="tool")
    ax.plot([0, p[0] * mm], [0, p[1] * mm], "r-", lw=2, label=f"shear plane, phi = {math.degrees(phi):.1f} deg")
    contact = np.array([[0.0, 0.0], result.contact_length * up]) * mm
    ax.plot(*contact.T, "k-", lw=4, label=f"contact length {result.contact_length * mm:.3f} mm")
    ax.set_aspect("equal")
    ax.set_xlim(-span * mm, 3 * t1 * mm)
    ax.set_ylim(-2 * t1 * mm, (chip_length * up[1] + 2 * t1) * mm)
    ax.set_xlabel("x [mm] (the tool moves in -x)")
    ax.set_ylabel("y [mm]")
    ax.set_title(title or "extended Oxley model")
    ax.text(0.02, 0.02, f"F_c = {result.Fc:.0f} N, F_t = {result.Ft:.0f} N\nT_AB = {result.T_AB - 273.15:.0f} C, "
            f"T_int = {result.T_int - 273.15:.0f} C", transform=ax.transAxes, fontsize=9, va="bottom")
    ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
