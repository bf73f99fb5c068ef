"""The plane body's picture drawn with Pillow (issue 20, :mod:`wendel.results.flat`): the colours are the cells'
values on the colour map, and a picture process told "plane" draws it without importing matplotlib (a solid
still gets its matplotlib picture from the same process)."""

import json
import subprocess
import sys

import meshio
import numpy as np
from PIL import Image

from wendel.results import flat


def _square(tmp_path, values):
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0]], float)
    cells = [("triangle", np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]))]
    vtu = tmp_path / "plane.vtu"
    meshio.write(vtu, meshio.Mesh(pts, cells, point_data={"u": np.zeros((5, 3))},
                                  cell_data={"vonMises": [np.asarray(values, float)]}))
    return vtu


def test_each_cell_is_drawn_in_the_colour_of_its_value(tmp_path):
    values = [1.0, 2.0, 3.0, 4.0]
    vtu = _square(tmp_path, values)
    png = tmp_path / "a.png"
    assert flat.plane_picture(meshio.read(vtu), png, "load factor 1")
    img = np.asarray(Image.open(png).convert("RGB")).reshape(-1, 3)
    assert Image.open(png).size == flat.SIZE
    area = {}
    for v, rgb in zip(values, flat.colours(np.array(values), 1.0, 4.0)):
        area[v] = int(np.all(img == rgb, axis=1).sum())
    # four triangles of a 590 x 590 pixel square (less their edges): each well over 50,000 pixels of its colour
    assert all(a > 50000 for a in area.values()), area
    assert max(area.values()) < 1.3 * min(area.values())
    # the lowest and the highest value are the two ends of viridis
    assert flat.colours(np.array([1.0, 4.0]), 1.0, 4.0).tolist() == [[68, 1, 84], [253, 231, 37]]


def test_a_solid_or_a_scalar_surface_is_left_to_matplotlib(tmp_path):
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    solid = meshio.Mesh(pts, [("tetra", np.array([[0, 1, 2, 3]]))], point_data={"u": np.zeros((4, 3))})
    assert not flat.plane_picture(solid, tmp_path / "s.png", "x")
    scalar = meshio.Mesh(pts[:3], [("triangle", np.array([[0, 1, 2]]))], point_data={"u": np.zeros(3)})
    assert not flat.plane_picture(scalar, tmp_path / "z.png", "x")
    assert not (tmp_path / "s.png").exists() and not (tmp_path / "z.png").exists()


def test_a_process_told_plane_draws_without_matplotlib_and_still_draws_a_solid(tmp_path):
    vtu = _square(tmp_path, [1.0, 2.0, 3.0, 4.0])
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]], float)
    solid = tmp_path / "solid.vtu"
    meshio.write(solid, meshio.Mesh(pts, [("tetra", np.array([[0, 1, 2, 3], [1, 2, 3, 4]]))],
                                    point_data={"u": 0.01 * pts}, cell_data={"vonMises": [np.array([1.0, 2.0])]}))
    req = [{"hint": "plane"}, {"vtu": str(vtu), "png": str(tmp_path / "plane.png"), "title": "t", "warp": 0.0}]
    code = ("import io, sys\nfrom wendel.results.pictures import serve_lines\n"
            "out = io.StringIO()\n"
            f"serve_lines('matplotlib', io.StringIO({json.dumps(''.join(json.dumps(r) + chr(10) for r in req))}), out)\n"
            "print(out.getvalue().split(), 'matplotlib.pyplot' in sys.modules)\n"
            f"serve_lines('matplotlib', io.StringIO({json.dumps(json.dumps({'vtu': str(solid), 'png': str(tmp_path / 'solid.png'), 'title': 't', 'warp': 0.0}) + chr(10))}), out)\n"
            "print(out.getvalue().split(), 'matplotlib.pyplot' in sys.modules)\n")
    lines = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120).stdout.splitlines()
    assert lines == ["['ok'] False", "['ok', 'ok'] True"], lines
    assert (tmp_path / "plane.png").stat().st_size > 10000 and (tmp_path / "solid.png").stat().st_size > 10000


def test_cells_of_other_kinds_in_the_file_do_not_shift_the_colours(tmp_path):
    """A VTU with boundary lines before the triangles (their own cell values): each triangle keeps its value."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, 0.5, 0]], float)
    mesh = meshio.Mesh(pts, [("line", np.array([[0, 1], [1, 2]])),
                             ("triangle", np.array([[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]))],
                       point_data={"u": np.zeros((5, 3))},
                       cell_data={"vonMises": [np.array([100.0, 100.0]), np.array([1.0, 2.0, 3.0, 4.0])]})
    png = tmp_path / "a.png"
    assert flat.plane_picture(mesh, png, "x")
    img = np.asarray(Image.open(png).convert("RGB")).reshape(-1, 3)
    for rgb in flat.colours(np.array([1.0, 2.0, 3.0, 4.0]), 1.0, 4.0):
        assert np.all(img == rgb, axis=1).sum() > 50000
