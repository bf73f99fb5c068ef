"""The deformed body drawn without pyvista (:func:`quick_picture`): a plane body with Pillow (:mod:`.flat`), a
solid as its coloured boundary faces and a scalar field on a plane as the surface z = u with matplotlib. Drawn
in the picture process (:mod:`.pictures`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import flat


def _faces(tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The boundary triangles of a tetrahedral mesh (faces of one tetrahedron only) and their tetrahedra.

    >>> f, owner = _faces(np.array([[0, 1, 2, 3], [1, 2, 3, 4]])); len(f), sorted(owner.tolist())
    (6, [0, 0, 0, 1, 1, 1])
    """
    local = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]])
    faces = tets[:, local].reshape(-1, 3)
    owner = np.repeat(np.arange(len(tets)), 4)
    _, first, counts = np.unique(np.sort(faces, axis=1), axis=0, return_index=True, return_counts=True)
    keep = first[counts == 1]
    return faces[keep], owner[keep]


def quick_picture(vtu: Path, png: Path, title: str, warp: float = 0.0, field: str | None = None,
                  deformed: bool = False) -> None:
    """The deformed body: a plane body with a vector displacement with Pillow (:func:`wendel.results.flat.plane_picture`),
    a solid as its coloured boundary faces and a scalar ``u`` on a plane as the surface z = u with matplotlib (0.6 s
    to start here, against 3 s for pyvista); coloured by ``field`` (von Mises by default) and scaled as
    :func:`~wendel.results.pictures.picture` does (``deformed``: the points are the current configuration already,
    as in updated-Lagrangian runs). The file is read once; matplotlib is imported only for what Pillow does not draw."""
    import meshio

    m = meshio.read(vtu)
    if flat.plane_picture(m, png, title, warp, field, deformed):
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    points = np.asarray(m.points, dtype=float)
    u = np.asarray(m.point_data["u"]) if "u" in m.point_data else np.zeros((len(points), 3))
    solid = any(b.type == "tetra" for b in m.cells)
    cells = np.concatenate([b.data for b in m.cells if b.type == ("tetra" if solid else "triangle")])
    field = field or ("vonMises" if "vonMises" in m.cell_data else None)
    values = np.concatenate([np.ravel(v) for v in m.cell_data[field]]) if field else None
    size = max(np.ptp(points, axis=0))
    fig = plt.figure(figsize=(9, 7), dpi=100)
    if u.ndim == 1:         # a scalar field on a plane (membrane, torsion): the surface z = u
        scale = warp or (0.3 * size / (float(np.abs(u).max()) or 1.0))
        xyz = points.copy()
        xyz[:, 2] = scale * u
        faces, owner = cells, np.arange(len(cells))
        field = field or "u"
        values = values if values is not None else u[cells].mean(axis=1)
        what = f"u x{scale:.3g} upwards"
    else:                   # a solid (flat.plane_picture draws every plane body with a vector u)
        scale = flat.warp_scale(u, size, warp, deformed, "u_total" in m.point_data)
        xyz = points + scale * u[:, :3]
        faces, owner = _faces(cells)
        what = "current configuration" if deformed else f"displacement x{scale:.3g}"
    ax = fig.add_subplot(projection="3d")
    colours = values[owner] if values is not None else np.zeros(len(faces))
    norm = plt.Normalize(colours.min(), colours.max())
    poly = Poly3DCollection(xyz[faces], facecolors=plt.cm.viridis(norm(colours)),
                            edgecolors="k" if len(faces) < 20000 else "none", linewidths=0.1)
    ax.add_collection3d(poly)
    lo, hi = xyz.min(axis=0), xyz.max(axis=0)
    ax.set_xlim(lo[0], hi[0]), ax.set_ylim(lo[1], hi[1]), ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(np.maximum(hi - lo, 1e-3 * max(hi - lo)))
    ax.view_init(elev=30, azim=-60)
    mappable = plt.cm.ScalarMappable(norm=norm, cmap="viridis")
    fig.colorbar(mappable, ax=ax, label=field or "", shrink=0.7)
    ax.set_title(f"{title} ({what})", fontsize=10)
    fig.savefig(png)
    plt.close(fig)
