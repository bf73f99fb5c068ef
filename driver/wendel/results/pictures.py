"""Pictures of a result: the deformed body (``deformed.png`` of a run), off-screen with pyvista
(:func:`picture`) or with matplotlib (:func:`quick_picture`: 0.6 s to import and draw a small mesh where
pyvista takes 3 s to import and open its first window); a plane body with Pillow (:mod:`.flat`: 0.2 s to
import, 0.03-0.07 s to draw). A run draws it in a :class:`Painter` process that starts with the run
(:func:`renderer` chooses)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .flat import warp_scale
from .quick import quick_picture      # Pillow for plane bodies, matplotlib for solids and z = u surfaces


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
        # true scale for visible deformations and remeshed bodies, magnified to 10 % of the size for small
        # ones, none for an updated-Lagrangian VTU (its points are the deformed body already)
        scale = warp_scale(np.asarray(grid.point_data["u"]), max(np.ptp(grid.points, axis=0)), warp, deformed,
                           "u_total" in grid.point_data)
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

    def plane(self) -> None:
        """Tell the process that the run's body is plane (2D or (r, z)): its pictures are drawn with Pillow, and
        matplotlib, imported beside the run for solids, is left (0.7-0.9 s of CPU on a 2-core machine)."""
        try:
            self.proc.stdin.write('{"hint": "plane"}\n')
            self.proc.stdin.flush()
        except OSError:         # it ended: the picture says so
            pass

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


def plane() -> None:
    """The run's body is plane: tell the picture process :func:`prestart` started (if any)."""
    for early in _EARLY:
        early.plane()


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
    ``stdout``, until ``stdin`` closes. ``matplotlib``: plane bodies are drawn with Pillow
    (:mod:`wendel.results.flat`), the rest with matplotlib, imported in a thread unless a ``{"hint": "plane"}``
    line came first (:meth:`Painter.plane`)."""
    import importlib
    import json
    import sys
    import threading

    if renderer == "matplotlib":
        import meshio  # noqa: F401 - warm-up (numpy and Pillow 0.2 s to import, matplotlib 0.7-0.9 s)

        plane = threading.Event()       # the driver's "plane" line: no matplotlib needed

        def _matplotlib():          # solids and z = u surfaces: matplotlib, imported beside the run
            for name in ("matplotlib", "matplotlib.pyplot", "mpl_toolkits.mplot3d.art3d"):
                if plane.is_set():
                    return
                importlib.import_module(name)
                if name == "matplotlib":
                    sys.modules["matplotlib"].use("Agg")

        threading.Thread(target=_matplotlib, daemon=True).start()
        draw = quick_picture
    else:
        _warm_up()
        draw = picture
    for line in stdin:
        try:
            req = json.loads(line)
            if req.get("hint") == "plane":          # Painter.plane: answered by nothing
                if renderer == "matplotlib":
                    plane.set()
                continue
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
