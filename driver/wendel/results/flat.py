"""A plane body's picture drawn with Pillow (issue 20): the deformed triangles coloured by a cell field, a
colour bar, a title and the extent of the axes, in about 0.05 s for a smoke mesh.

matplotlib's picture of the same body (:func:`wendel.results.quick.quick_picture`) needs matplotlib and
pyplot imported (0.7-0.9 s here), which a smoke-size run waited for at its end (0.4-0.7 s of a 1.4 s run);
numpy and Pillow import in 0.2 s. The picture process draws plane bodies with a vector displacement here
(``deformed.png`` of 2D and (r, z) runs) and everything else (solids, the scalar surface z = u) with
matplotlib or pyvista as before. Same scaling of the displacement, same colours (viridis, sampled at 17
points and interpolated linearly), same 900 x 700 pixels.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

SIZE = (900, 700)
"""Width and height of the picture in pixels (matplotlib's 9 x 7 inches at 100 dpi)."""

VIRIDIS = np.array([(68, 1, 84), (72, 24, 106), (71, 45, 123), (66, 64, 134), (59, 82, 139), (51, 99, 141),
                    (44, 114, 142), (38, 130, 142), (33, 145, 140), (31, 160, 136), (40, 174, 128),
                    (63, 188, 115), (94, 201, 98), (132, 212, 75), (173, 220, 48), (216, 226, 25),
                    (253, 231, 37)], dtype=float)
"""The viridis colour map (van der Walt and Smith, matplotlib's default) at 0, 1/16, ..., 1 (sRGB 0-255)."""

EDGES_BELOW = 20000
"""Cells drawn with their edges below this many (as the matplotlib picture)."""

SUPERSAMPLE = 2
"""Drawn at this multiple of the size and reduced (the mean of each s x s block): smooth edges."""


def colours(values: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """RGB (uint8, one row per value) of ``values`` on the colour map from ``lo`` to ``hi``; grey where a
    value is not finite.

    >>> colours(np.array([0.0, 1.0, 0.5, np.nan]), 0.0, 1.0).tolist()
    [[68, 1, 84], [253, 231, 37], [33, 145, 140], [128, 128, 128]]
    """
    t = np.clip((values - lo) / (hi - lo), 0.0, 1.0) if hi > lo else np.full(len(values), 0.5)
    x = np.nan_to_num(t, nan=0.0) * (len(VIRIDIS) - 1)
    i = np.minimum(x.astype(int), len(VIRIDIS) - 2)
    w = (x - i)[:, None]
    rgb = np.rint((1.0 - w) * VIRIDIS[i] + w * VIRIDIS[i + 1]).astype(np.uint8)
    rgb[~np.isfinite(values)] = 128
    return rgb


def ticks(lo: float, hi: float, n: int = 5) -> list[float]:
    """About ``n`` round values in [lo, hi] (steps of 1, 2, 2.5 or 5 times a power of ten).

    >>> ticks(0.0, 1.0)
    [0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
    >>> ticks(-3e-4, 7e-4)
    [-0.0002, 0.0, 0.0002, 0.0004, 0.0006]
    """
    if not hi > lo:
        return [lo]
    raw = (hi - lo) / n
    power = 10.0 ** np.floor(np.log10(raw))
    step = power * min((m for m in (1.0, 2.0, 2.5, 5.0, 10.0) if m * power >= raw * 0.999))
    first = np.ceil(lo / step - 1e-9) * step
    count = int(np.floor((hi - first) / step + 1e-9)) + 1
    return [float(np.round(first + k * step, 12)) + 0.0 for k in range(count)]


def _font(size: int):
    """DejaVu Sans (shipped with matplotlib, found without importing it), else Pillow's own font."""
    from PIL import ImageFont

    spec = importlib.util.find_spec("matplotlib")
    for root in (spec.submodule_search_locations or []) if spec else []:
        path = Path(root) / "mpl-data" / "fonts" / "ttf" / "DejaVuSans.ttf"
        if path.is_file():
            return ImageFont.truetype(str(path), size)
    return ImageFont.load_default()


def draw(points: np.ndarray, cells: np.ndarray, values: np.ndarray | None, title: str, label: str,
         png: Path) -> None:
    """Write ``png``: the triangles ``cells`` on the plane ``points`` (n x 2) coloured by the cell
    ``values`` (or outlined only, None), a colour bar named ``label``, ``title`` above."""
    from PIL import Image, ImageDraw

    s = SUPERSAMPLE
    width, height = SIZE
    img = Image.new("RGB", (width * s, height * s), "white")
    pen = ImageDraw.Draw(img)
    font, small = _font(13 * s), _font(11 * s)
    # the plot's box: left margin for the y values, right for the colour bar
    box = np.array([80, 50, 700, 640], dtype=float) * s
    lo, hi = points.min(axis=0), points.max(axis=0)
    span = np.maximum(hi - lo, 1e-300)
    scale = min((box[2] - box[0]) / span[0], (box[3] - box[1]) / span[1])
    used = span * scale
    origin = np.array([box[0] + 0.5 * (box[2] - box[0] - used[0]), box[3] - 0.5 * (box[3] - box[1] - used[1])])
    xy = np.column_stack([origin[0] + (points[:, 0] - lo[0]) * scale, origin[1] - (points[:, 1] - lo[1]) * scale])
    tri = xy[cells]
    if values is not None:
        vmin, vmax = float(np.nanmin(values)), float(np.nanmax(values))
        rgb = colours(values, vmin, vmax)
        fill = [tuple(c) for c in rgb.tolist()]
        # edges a darker shade of their cell's colour: a fine graded region keeps its colour (black lines
        # would cover it), as matplotlib's thin anti-aliased edges do
        edges = [tuple(c) for c in (0.45 * rgb).astype(np.uint8).tolist()] if len(cells) < EDGES_BELOW \
            else [None] * len(cells)
    else:
        fill, edges = [None] * len(cells), [(0, 0, 0)] * len(cells)
    for corners, f, e in zip(tri.round(1).tolist(), fill, edges):
        pen.polygon([tuple(p) for p in corners], fill=f, outline=e)
    # the extent of the body on both axes: a frame with round values
    x0, y1, x1, y0 = origin[0], origin[1], origin[0] + used[0], origin[1] - used[1]
    pen.rectangle([x0 - 4 * s, y0 - 4 * s, x1 + 4 * s, y1 + 4 * s], outline=(90, 90, 90), width=s)
    # about one value per 90 pixels across, 60 pixels up: the labels of a narrow body do not run together
    for v in ticks(float(lo[0]), float(hi[0]), int(np.clip(used[0] / (90 * s), 2, 6))):
        x = origin[0] + (v - lo[0]) * scale
        pen.line([x, y1 + 4 * s, x, y1 + 9 * s], fill=(0, 0, 0), width=s)
        pen.text((x, y1 + 11 * s), f"{v:.4g}", fill=(0, 0, 0), font=small, anchor="ma")
    for v in ticks(float(lo[1]), float(hi[1]), int(np.clip(used[1] / (60 * s), 2, 8))):
        y = origin[1] - (v - lo[1]) * scale
        pen.line([x0 - 9 * s, y, x0 - 4 * s, y], fill=(0, 0, 0), width=s)
        pen.text((x0 - 11 * s, y), f"{v:.4g}", fill=(0, 0, 0), font=small, anchor="rm")
    pen.text((width * s / 2, 18 * s), title, fill=(0, 0, 0), font=font, anchor="ma")
    if values is not None:
        _colour_bar(pen, s, vmin, vmax, label, font, small)
    # a box filter's mean of s x s pixels and zlib's fastest level: 0.04 s each faster than Lanczos and level 6
    img.reduce(s).save(png, compress_level=1)


def _colour_bar(pen, s: int, vmin: float, vmax: float, label: str, font, small) -> None:
    """A vertical colour bar at the right, with its values and ``label`` above it."""
    left, top, right, bottom = 745 * s, 90 * s, 770 * s, 600 * s
    rows = np.arange(bottom - top)
    rgb = colours(vmin + (vmax - vmin) * (1.0 - rows / max(len(rows) - 1, 1)), vmin, vmax)
    for r, c in zip(rows.tolist(), rgb.tolist()):
        pen.line([left, top + r, right, top + r], fill=tuple(c))
    pen.rectangle([left, top, right, bottom], outline=(0, 0, 0), width=s)
    for v in ticks(vmin, vmax) if vmax > vmin else [vmin]:
        y = bottom - (v - vmin) / (vmax - vmin) * (bottom - top) if vmax > vmin else (top + bottom) / 2
        pen.line([right, y, right + 5 * s, y], fill=(0, 0, 0), width=s)
        pen.text((right + 8 * s, y), f"{v:.4g}", fill=(0, 0, 0), font=small, anchor="lm")
    pen.text(((left + right) / 2, top - 14 * s), label, fill=(0, 0, 0), font=font, anchor="md")


def warp_scale(u, size: float, warp: float, deformed: bool, total: bool) -> float:
    """The factor the displacement ``u`` is drawn with on a body of ``size``: ``warp`` if given; true scale (1)
    for a visible deformation or a remeshed body (``total``: its mesh is the deformed body already), else
    magnified to a tenth of the size; 0 when the points are the current configuration (``deformed``).

    >>> warp_scale(np.array([[0.001, 0.0]]), 1.0, 0.0, False, False), warp_scale(np.array([[0.1, 0.0]]), 1.0, 0.0, False, False)
    (100.0, 1.0)
    """
    if deformed:
        return 0.0
    umax = float(np.abs(u).max()) or 1.0
    return warp or (1.0 if umax >= 0.05 * size or total else 0.1 * size / umax)


def plane_picture(mesh, png: Path, title: str, warp: float = 0.0, field: str | None = None,
                  deformed: bool = False) -> bool:
    """Draw ``mesh`` (a meshio mesh read from a run's VTU) if it is a plane body with a vector displacement
    (else False: the caller draws it otherwise), scaled and titled as the matplotlib picture."""
    points = np.asarray(mesh.points, dtype=float)
    u = np.asarray(mesh.point_data["u"]) if "u" in mesh.point_data else np.zeros((len(points), 3))
    if u.ndim == 1 or any(b.type == "tetra" for b in mesh.cells):
        return False
    cells = np.concatenate([b.data for b in mesh.cells if b.type == "triangle"])
    field = field or ("vonMises" if "vonMises" in mesh.cell_data else None)
    values = np.concatenate([np.ravel(v) for b, v in zip(mesh.cells, mesh.cell_data[field])
                             if b.type == "triangle"]).astype(float) if field else None
    u = u[:, :2]
    scale = warp_scale(u, max(np.ptp(points, axis=0)), warp, deformed, "u_total" in mesh.point_data)
    what = "current configuration" if deformed else f"displacement x{scale:.3g}"
    draw(points[:, :2] + scale * u, cells, values, f"{title} ({what})", field or "", png)
    return True
