"""CG and DG in one mesh (``discretization.region``, edp/lib/dg.idp): DG cells inside the box, CG outside, the
SIPG face terms coupling them by Nitsche's method; the manufactured solution converges at the P1 rates, the
field is continuous in the CG cells only, and what the mixed form does not join is refused."""

from __future__ import annotations

import csv
import json

import pytest

from wendel.results.study import study
from wendel.scene import SceneError, load

from conftest import WORKFLOWS, edit


def test_cg_and_dg_in_one_mesh_converge_and_the_cg_part_is_continuous(tmp_path):
    # measured (h = 0.2, 0.1, 0.05): L2 1.70e-1, 4.83e-2, 1.25e-2 (rates 1.82, 1.95), H1 rates 0.99, 1.00;
    # 524 unknowns at h = 0.2 against 1,200 DG and 242 CG DoFs
    root = study(WORKFLOWS / "dg-mixed.toml", levels=3, smoke=True, out=tmp_path / "study", progress=lambda *_: None)
    rows = list(csv.DictReader(open(root / "study.csv")))
    assert abs(float(rows[-1]["rate_l2"]) - 2) <= 0.2 and abs(float(rows[-1]["rate_h1"]) - 1) <= 0.2, rows[-1]
    for level, row in enumerate(rows):
        rec = json.loads((root / f"level-{level}" / "fem" / "inc-0001" / "record.json").read_text())
        assert rec["dg_region_cells"] == 50 * 4 ** level                  # the centre quarter of the square
        assert rec["dg_jump_cg"] < 1e-12 and rec["dg_jump_dg"] > 1e-4      # continuous outside, not inside
        assert rec["dg_mixed_unknowns"] < int(row["dofs"]) / 2
    # between the pure methods at h = 0.2 (dg-mms: L2 1.59e-1, smoke-mms: 1.77e-1)
    assert 0.16 < float(rows[0]["error_l2"]) < 0.175


@pytest.mark.parametrize("change, message", [
    (("region = [[-0.5, -0.5], [0.5, 0.5]]", "region = [[0.5, -0.5], [-0.5, 0.5]]"), "discretization.region"),
    (("region = [[-0.5, -0.5], [0.5, 0.5]]", "region = [[-0.5, -0.5, 0.0], [0.5, 0.5]]"), "discretization.region"),
    (("region = [[-0.5, -0.5], [0.5, 0.5]]", "separation_stress = 1e6\nregion = [[-0.5, -0.5], [0.5, 0.5]]"),
     "elastic only, without separation_stress"),
    (("[discretization]", "[plasticity]\nsigma0 = 1.0\n\n[discretization]"), "elastic only"),
    (("kind = \"dg\"", "kind = \"cg\""), "discretization.region needs discretization.kind = 'dg'"),
])
def test_what_the_mixed_form_does_not_join_is_refused(scene_file, change, message):
    path = scene_file(edit((WORKFLOWS / "dg-mixed.toml").read_text(), *change))
    with pytest.raises(SceneError) as err:
        load(path)
    assert message in str(err.value) and str(path) in str(err.value)
