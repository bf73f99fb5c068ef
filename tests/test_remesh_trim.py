"""remesh.trim (cutting.trim_chip): material left out of the new meshes, the cut's edges labelled."""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from meshes.cutting import orthogonal_cutting  # noqa: E402
from meshes.labels import LABELS  # noqa: E402
from wendel.remesh import mesher  # noqa: E402
from wendel.scene import SceneError, load  # noqa: E402


def _squares(corners):
    """Unit squares with lower-left ``corners``, two triangles each, sharing their nodes."""
    index, pts, tri = {}, [], []
    node = lambda p: index.setdefault(p, len(index)) if p in index or not pts.append(p) else index[p]
    for x, y in corners:
        a, b, c, d = (node((x, y)), node((x + 1, y)), node((x + 1, y + 1)), node((x, y + 1)))
        tri += [[a, b, c], [a, c, d]]
    return np.array(pts, dtype=float), np.array(tri)


def test_trim_leaves_out_the_far_material_above_and_a_piece_it_leaves_hanging():
    """A base square, a strip of four on it and a square hanging under the strip's far end: the far half of the strip
    goes (far and above), and so does the hanging square (below the line, but cut off from the body)."""
    pts, tri = _squares([(0, 0), (0, 1), (1, 1), (2, 1), (3, 1), (3, 0)])
    keep = mesher.trim_cells(pts, tri, [0.5, 0.0], 2.2, 1.0)
    assert keep.tolist() == [True] * 6 + [False] * 6


def test_a_trimmed_remesh_meshes_what_is_left_and_labels_the_cut_as_the_named_boundary(tmp_path):
    """The workpiece of a cut, trimmed above 0.05 mm and farther than 0.5 mm from a point on its top: the new mesh's
    area is the old one less the cells left out (to the chords of the cut), one body, every boundary edge labelled,
    the cut's edges with free_surface's label, no node in the trimmed region."""
    built = orthogonal_cutting(tmp_path / "w.msh", h=1e-4, fine=0.5)
    pts, _, cells, _, facets, tags = mesher.read_mesh(built.path)
    trim = {"point": [1.0e-3, 0.0], "radius": 0.5e-3, "above": 0.05e-3, "label": "free_surface"}
    rep = mesher.remesh(pts[:, :2], built.path, tmp_path / "new.msh", 1e-4, trim=trim)
    assert rep["trimmed_elements"] > 20 and rep["bodies"] == 1 and rep["unlabelled_facets"] == 0
    assert rep["measure_new"] == pytest.approx(rep["measure_old"] - rep["trimmed_measure"], rel=1e-3)
    assert rep["measure_new"] < rep["measure_old"] - 0.5 * rep["trimmed_measure"]
    y, _, new_cells, _, new_facets, new_tags = mesher.read_mesh(tmp_path / "new.msh")
    far = (np.hypot(y[:, 0] - 1.0e-3, y[:, 1]) > 0.5e-3 + 0.6e-4) & (y[:, 1] > 0.05e-3 + 0.6e-4)
    assert not far.any()
    free = LABELS["free_surface"]
    cut_edges = [f for f, t in zip(new_facets.tolist(), new_tags.tolist()) if t == free
                 and min(y[f, 1]) < 0.15e-3 - 1e-9]          # free_surface below the layer's top: the cut
    assert cut_edges
    with pytest.raises(ValueError, match="remesh.trim.label = 'chip' is none of the mesh's names"):
        mesher.remesh(pts[:, :2], built.path, tmp_path / "bad.msh", 1e-4, trim={**trim, "label": "chip"})


def test_cutting_trim_chip_reaches_the_remeshes_and_a_bad_label_is_refused_by_name(tmp_path):
    from wendel.cutting.fe import fe_scene
    assert fe_scene(load(ROOT / "workflows" / "cutting-aisi1045-steady.toml")).remesh.trim is None     # opt-in
    fe = fe_scene(load(ROOT / "workflows" / "cutting-ti6al4v-steady.toml"))      # trim_chip = 4
    t = fe.remesh.trim
    assert t.label == "free_surface" and fe.remesh.zones_follow == "tool"
    assert t.radius == pytest.approx(4 * 0.1) and t.above == pytest.approx(t.point[1] + 1.05 * 0.1)   # mm
    bad = (ROOT / "workflows" / "upsetting.toml").read_text() + \
        '\n[remesh.trim]\npoint = [0.0, 0.0]\nradius = 1.0\nabove = 0.0\nlabel = "chip"\n'
    (tmp_path / "b.toml").write_text(bad)
    with pytest.raises(SceneError, match=r"remesh\.trim\.label: builder 'rectangle' names left"):
        load(tmp_path / "b.toml")
    assert math.isfinite(t.radius)
    (tmp_path / "b.toml").write_text(bad.replace('label = "chip"', 'label = "top"').replace("radius = 1.0", "radius = nan"))
    with pytest.raises(SceneError, match=r"remesh\.trim\.radius"):
        load(tmp_path / "b.toml")
