"""Pictures of a result: the deformed body (``deformed.png`` of a run), off-screen with pyvista
(:func:`picture`) or with matplotlib (:func:`quick_picture`: 0.6 s to import and draw a small mesh where
pyvista takes 3 s to import and open its first window). A run draws it in a :class:`Painter` process that
starts with the run (:func:`renderer` chooses)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np


def picture(vtu: Path, png: Path, title: str, warp: float = 0.0, field: str | None = None,
            deformed: bool = False) -> None:
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
        if deformed:
            scale = 0.0         # updated-Lagrangian VTU: the points are the deformed body already
        grid = grid.warp_by_vector("u", factor=scale)
        title = f"{title} ({'current configuration' if deformed else f'displacement x{scale:.3g}'})"
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
    """The deformed body drawn with matplotlib (0.6 s to start here, against 3 s for pyvista): a plane body
    as coloured triangles, a solid as its coloured boundary faces, a scalar ``u`` on a plane as the surface
    z = u; coloured by ``field`` (von Mises by default) and scaled as :func:`picture` does (``deformed``: the
    points are the current configuration already, as in updated-Lagrangian runs)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import meshio
    from matplotlib.tri import Triangulation

    m = meshio.read(vtu)
    points = np.asarray(m.points, dtype=float)
    u = np.asarray(m.point_data["u"]) if "u" in m.point_data else np.zeros((len(points), 3))
    solid = any(b.type == "tetra" for b in m.cells)
    kind = "tetra" if solid else "triangle"
    cells = np.concatenate([b.data for b in m.cells if b.type == kind])
    field = field or ("vonMises" if "vonMises" in m.cell_data else None)
    values = np.concatenate([np.ravel(v) for v in m.cell_data[field]]) if field else None
    size = max(np.ptp(points, axis=0))
    fig = plt.figure(figsize=(9, 7), dpi=100)
    if u.ndim == 1 or solid:
        if u.ndim == 1:         # a scalar field on a plane (membrane, torsion): the surface z = u
            scale = warp or (0.3 * size / (float(np.abs(u).max()) or 1.0))
            xyz = points.copy()
            xyz[:, 2] = scale * u
            faces, owner = cells, np.arange(len(cells))
            field = field or "u"
            values = values if values is not None else u[cells].mean(axis=1)
            what = f"u x{scale:.3g} upwards"
        else:
            umax = float(np.abs(u).max()) or 1.0
            scale = warp or (1.0 if umax >= 0.05 * size or "u_total" in m.point_data else 0.1 * size / umax)
            scale = 0.0 if deformed else scale
            xyz = points + scale * u[:, :3]
            faces, owner = _faces(cells)
            what = "current configuration" if deformed else f"displacement x{scale:.3g}"
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

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
    else:
        u = u[:, :2]
        umax = float(np.abs(u).max()) or 1.0
        large = umax >= 0.05 * size or "u_total" in m.point_data
        scale = 0.0 if deformed else warp or (1.0 if large else 0.1 * size / umax)
        p = points[:, :2] + scale * u
        ax = fig.add_subplot()
        style = {"edgecolors": "k", "linewidth": 0.2} if len(cells) < 20000 else {}
        tri = Triangulation(p[:, 0], p[:, 1], cells)
        if values is not None:
            mesh = ax.tripcolor(tri, facecolors=values, cmap="viridis", **style)
            fig.colorbar(mesh, ax=ax, label=field)
        else:
            ax.triplot(tri, color="k", linewidth=0.3)
        ax.set_aspect("equal")
        ax.set_title(f"{title} ({'current configuration' if deformed else f'displacement x{scale:.3g}'})",
                     fontsize=10)
    fig.savefig(png)
    plt.close(fig)


BIG_MESH = 5e6
"""Mesh files above this many bytes (about 50k elements) are drawn with pyvista: its 3 s start is hidden
behind their solve, and it draws large meshes faster than matplotlib."""


def renderer(mesh_file: Path) -> str:
    """The renderer for a run on ``mesh_file``: matplotlib (0.6 s to start) unless the mesh is big."""
    try:
        big = Path(mesh_file).stat().st_size > BIG_MESH
    except OSError:
        big = False
    return "pyvista" if big else "matplotlib"


class Painter:
    """A picture process started when a run starts: it imports pyvista and opens its off-screen window (about
    3 s here, most of a smoke run's wall time when done at the end) or matplotlib (0.6 s) while FreeFEM
    solves, so that the run ends with the render alone (0.2 s for a smoke mesh).

    The process reads one request per line on its stdin and answers ``ok`` or the error on its stdout; it
    ends when its stdin closes (also when the driver dies). ``with Painter() as p: p.paint(...)``.
    """

    def __init__(self, renderer: str = "matplotlib"):
        """``renderer``: ``matplotlib`` (:func:`quick_picture`) or ``pyvista`` (:func:`picture`); see
        :func:`renderer`."""
        import subprocess
        import sys

        self.renderer = renderer
        # a run forked by a sweep's warm server forks it too (matplotlib imported); else a new interpreter,
        # in its own session: Ctrl-C stops the driver, whose closing of stdin then ends this process
        warm = sys.modules.get("wendel.sweep.warm")
        self.proc = (warm and warm.fork_painter(renderer)) or subprocess.Popen([sys.executable, "-m", "wendel.results.pictures", renderer],
                                     stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                                     start_new_session=True)

    def paint(self, vtu: Path, png: Path, title: str, warp: float = 0.0, deformed: bool = False) -> None:
        """Render ``vtu`` into ``png`` (as :func:`picture`); raise RuntimeError if the process could not."""
        import json

        try:
            self.proc.stdin.write(json.dumps({"vtu": str(vtu), "png": str(png), "title": title,
                                              "warp": warp, "deformed": deformed}) + "\n")
            self.proc.stdin.flush()
            answer = self.proc.stdout.readline().strip()
        except OSError as exc:
            answer = f"picture process ended: {exc}"
        if answer != "ok":
            raise RuntimeError(f"picture {png}: {answer or 'picture process ended'}")

    def close(self, at_once: bool = False) -> None:
        """End the process: it ends by itself when its stdin closes (after its start if it is still
        starting); killed after 5 s, or ``at_once`` (the run stopped short)."""
        import contextlib
        import subprocess

        with contextlib.suppress(OSError):
            self.proc.stdin.close()
        try:
            self.proc.wait(timeout=0 if at_once else 5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()

    def __enter__(self):
        return self

    def __exit__(self, exc_type, *exc):
        self.close(at_once=exc_type is not None)


_EARLY: list[Painter] = []


def prestart(renderer: str = "matplotlib") -> None:
    """Start a picture process before the mesh exists (its imports, 0.6 s here, overlap the driver's set-up
    and meshing); :func:`painter` hands it to the run."""
    if not _EARLY:
        _EARLY.append(Painter(renderer))


def painter(renderer: str) -> Painter:
    """A picture process for ``renderer``: the one :func:`prestart` started if it is alive and the same
    renderer (else it is stopped), or a new one."""
    while _EARLY:
        early = _EARLY.pop()
        if early.renderer == renderer and early.proc.poll() is None:
            return early
        early.close(at_once=True)
    return Painter(renderer)


def serve_lines(renderer: str, stdin, stdout) -> None:
    """Warm up (import, one off-screen render), then one picture per request line of ``stdin``, answered on
    ``stdout``, until ``stdin`` closes."""
    import json

    if renderer == "matplotlib":
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot  # noqa: F401 - warm-up
        import meshio  # noqa: F401

        draw = quick_picture
    else:
        _warm_up()
        draw = picture
    for line in stdin:
        try:
            req = json.loads(line)
            draw(Path(req["vtu"]), Path(req["png"]), req["title"], req["warp"], deformed=req.get("deformed", False))
            answer = "ok"
        except Exception as exc:        # noqa: BLE001 - reported to the driver, which raises it
            answer = f"{type(exc).__name__}: {exc}".replace("\n", " ")
        stdout.write(answer + "\n")
        stdout.flush()


def _serve() -> None:
    """The picture process (:func:`serve_lines` on its standard streams)."""
    import sys

    serve_lines(sys.argv[1] if sys.argv[1:] == ["matplotlib"] else "pyvista", sys.stdin, sys.stdout)
    # stdin closed: the driver waits for this exit; skip the interpreter's tear-down of matplotlib or VTK
    # (0.1 s here, in the run's wall time) - every picture is written and answered
    os._exit(0)


def _warm_up() -> None:
    """Import pyvista and render once off-screen (the first window costs ~1.8 s here)."""
    os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    import pyvista as pv

    pv.OFF_SCREEN = True
    try:                # a failure shows again at the real picture
        warm = pv.Plotter(off_screen=True, window_size=(900, 700))
        warm.add_mesh(pv.Sphere(), scalars=None)
        warm.add_text("warm-up", font_size=10)
        warm.screenshot(None, return_img=False)
        warm.close()
    except Exception:   # noqa: BLE001
        pass


if __name__ == "__main__":
    _serve()
