"""Interior penalty DG elasticity (``[discretization] kind = "dg"``, edp/lib/dg.idp): the module is compiled
only when asked, the manufactured solution converges at k + 1 (L2) and k (broken H1) for P1 and P2, a penalty
below the stability bound is warned about, and what DG does not join is refused when the scene is read."""

from __future__ import annotations

import csv
import json

import pytest

from wendel.loop import run
from wendel.results.study import study
from wendel.scene import SceneError, load

from conftest import WORKFLOWS, edit


def test_a_dg_scene_compiles_the_dg_module_and_the_elastic_cg_scene_does_not(tmp_path):
    from test_entry import MODULES, compiled

    found, switches, record = compiled(tmp_path / "dg", "dg-mms.toml")
    assert found & set(MODULES) == {"dg"}, found
    assert switches == ["-Ddimension=2", "-DPk=P1dc", "-DWITHDG=1"]
    assert record["dg_gamma_mu"] == 20 and record["dg_gamma_min"] == 6
    found, switches, _ = compiled(tmp_path / "cg", "smoke-mms.toml")
    assert "dg" not in found and "-DWITHDG=1" not in switches


@pytest.mark.parametrize("scene_name, order, levels", [("dg-mms.toml", 1, 3), ("dg-mms-p2.toml", 2, 2)])
def test_dg_manufactured_solution_converges_at_the_element_order(tmp_path, scene_name, order, levels):
    # measured (h = 0.2, 0.1, 0.05): P1 L2 rates 1.82, 1.95, H1 1.00, 1.00; P2 L2 3.20, H1 1.98
    root = study(WORKFLOWS / scene_name, levels=levels, smoke=True, out=tmp_path / "study", progress=lambda *_: None)
    rows = list(csv.DictReader(open(root / "study.csv")))
    assert len(rows) == levels
    assert abs(float(rows[-1]["rate_l2"]) - (order + 1)) <= 0.2, rows[-1]
    assert abs(float(rows[-1]["rate_h1"]) - order) <= 0.2, rows[-1]
    # DG has three (six) DoFs per triangle and component, none shared: 200 triangles at h = 0.2
    assert int(rows[0]["dofs"]) == 2 * (order + 1) * (order + 2) // 2 * 200


def test_a_penalty_below_the_stability_bound_is_warned_about_and_spoils_the_solution(tmp_path, scene_file, quiet):
    text = (WORKFLOWS / "dg-mms.toml").read_text()
    low = scene_file(edit(edit(text, "gamma_mu = 20.0 ", "gamma_mu = 0.5 "), "gamma_lambda = 20.0 ",
                          "gamma_lambda = 0.5 "), "low.toml")
    root = run(low, smoke=True, out=tmp_path / "low", png=False, progress=quiet)
    summary = json.loads((root / "summary.json").read_text())
    assert ("discretization.gamma_mu = 0.5 is below the sufficient stability bound 6 of P1 DG in 2D (dg.idp): "
            "the discrete problem may not be coercive") in summary["warnings"]
    assert any("gamma_lambda = 0.5" in w for w in summary["warnings"])
    assert "below the sufficient stability bound 6" in (root / "freefem.log").read_text()
    good = run(WORKFLOWS / "dg-mms.toml", smoke=True, out=tmp_path / "good", png=False, progress=quiet)
    good_summary = json.loads((good / "summary.json").read_text())
    assert not any("stability bound" in w for w in good_summary["warnings"])
    # measured at h = 0.2: relative H1 error 0.735 at gamma = 0.5 against 0.297 at gamma = 20
    bad_h1 = summary["errors"]["error_h1_relative"]
    assert bad_h1 > 2 * good_summary["errors"]["error_h1_relative"], (bad_h1, good_summary["errors"])


@pytest.mark.parametrize("change, message", [
    (("[discretization]", "[plasticity]\nsigma0 = 1.0\n\n[discretization]"), "elastic scenes only; remove [plasticity]"),
    (("solver = \"direct\"", "solver = \"ffddm\""), "numerics.solver = 'direct'"),
    (("order = 1                # P1dc", "order = 3"), "discretization.order"),
    (("gamma_mu = 20.0 ", "gamma_mu = -1.0 "), "discretization.gamma_mu"),
    (("kind = \"dg\"", "kind = \"hdg\""), "discretization.kind"),
    (("[numerics]", "[elasticity]\norder = 2\n\n[numerics]"), "elasticity.order = 1"),
])
def test_what_dg_does_not_join_is_refused_when_the_scene_is_read(scene_file, change, message):
    path = scene_file(edit((WORKFLOWS / "dg-mms.toml").read_text(), *change))
    with pytest.raises(SceneError) as err:
        load(path)
    assert message in str(err.value) and str(path) in str(err.value)
