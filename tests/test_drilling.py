"""Drilling: material removal by geometry (meshes/drilling.py) and the process loop (wendel.drilling)."""

from __future__ import annotations

import math

import meshio
import numpy as np
import pytest

from wendel.meshes import LABELS
from wendel.meshes import drilling as D
from wendel.remeshing import cell_volumes

R, DIA, ANGLE = 0.003, 0.006, 118.0


def _facet_labels(mesh, kind):
    return set(np.unique(mesh.cell_data_dict["gmsh:physical"][kind]).tolist())


@pytest.mark.parametrize("depth", [0.001, 0.004, 0.012])
def test_removed_volume_3d_block(tmp_path, depth):
    """Block minus the bore: the removed volume equals V(d) within the chord error of the meshed circle."""
    h_bore = 0.0008
    b = D.drilled(tmp_path / "m.msh", "block", depth=depth, diameter=DIA, point_angle=ANGLE,
                  x=(-0.012, 0.012), y=(-0.012, 0.012), height=0.02, h=0.003, h_bore=h_bore)
    m = meshio.read(b.path)
    removed = 0.024 * 0.024 * 0.02 - cell_volumes(m.points, m.cells_dict["tetra"]).sum()
    exact = D.bore_volume(depth, R, ANGLE)
    # an inscribed polygon of side h misses (h/r)^2/6 of a disc of radius r (the wetted radius of the
    # cone while the shoulder is not in); allow three times that
    r_wet = min(R, depth * math.tan(math.radians(ANGLE) / 2))
    assert abs(removed - exact) <= exact * (h_bore / r_wet) ** 2 / 2
    assert removed <= exact * (1 + 1e-9)
    labels = _facet_labels(m, "triangle")
    assert LABELS["bore_bottom"] in labels and LABELS["top"] in labels
    assert (LABELS["bore_wall"] in labels) == (depth > D.cone_height(R, ANGLE))


def test_bore_areas_on_the_mesh(tmp_path):
    """The re-tagged bore wall and bottom have the areas of the analytic bore (chord error)."""
    depth = 0.01
    b = D.drilled(tmp_path / "m.msh", "cylinder", depth=depth, diameter=DIA, radius=0.012, height=0.02,
                  h=0.003, h_bore=0.0006)
    m = meshio.read(b.path)
    tags = m.cell_data_dict["gmsh:physical"]["triangle"]
    tri = m.cells_dict["triangle"]
    p = m.points
    area = 0.5 * np.linalg.norm(np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]]), axis=1)
    wall, bottom = D.bore_areas(depth, R, ANGLE)
    assert area[tags == LABELS["bore_wall"]].sum() == pytest.approx(wall, rel=0.02)
    assert area[tags == LABELS["bore_bottom"]].sum() == pytest.approx(bottom, rel=0.02)


@pytest.mark.parametrize("depth", [0.0, 0.001, 0.004, 0.012])
def test_removed_volume_axisymmetric_section(tmp_path, depth):
    """(r, z) section: the removed volume 2 pi int r dA equals V(d) to round-off (straight profile edges)."""
    b = D.drilled_section(tmp_path / "s.msh", depth=depth, diameter=DIA, point_angle=ANGLE, radius=0.012,
                          height=0.02, h=0.002, h_bore=0.0005)
    m = meshio.read(b.path)
    tri, p = m.cells_dict["triangle"], m.points[:, :2]
    vol = (2 * math.pi * p[tri].mean(axis=1)[:, 0] * cell_volumes(p, tri)).sum()
    assert math.pi * 0.012 ** 2 * 0.02 - vol == pytest.approx(D.bore_volume(depth, R, ANGLE), rel=1e-9, abs=1e-15)
    labels = _facet_labels(m, "line")
    assert {LABELS[n] for n in ("top", "bottom", "outer", "symmetry_x")} <= labels
    assert (LABELS["bore_bottom"] in labels) == (depth > 0)
