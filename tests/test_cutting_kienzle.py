"""The FE Kienzle campaign (workflows/campaigns/cutting-kienzle.toml, `wendel bench cutting-kienzle`): the sweep file
plans, and the fit step on a real sweep of two short FE cuts of the steel scene (h = 0.1 and 0.15 mm, 15 um of
travel each, FreeFEM + gmsh) gives each cut's steady F_c in sweep.csv and finite k_c1.1 and m_c beside Oxley's
and the catalogue's."""

from __future__ import annotations

import csv
import math

from wendel.cli import main
from wendel.sweep.plan import load_sweep

from conftest import WORKFLOWS

CAMPAIGN = WORKFLOWS / "campaigns" / "cutting-kienzle.toml"


def test_the_kienzle_campaign_plans_cuts_that_scale_with_h():
    from wendel.cutting.fe import fe_scene
    from wendel.scene import parse

    sweep = load_sweep(CAMPAIGN)
    assert len(sweep.runs) == 8 and {r.params["cutting.rake"] for r in sweep.runs} == {-7.0, 0.0}
    for r in sweep.runs:
        p = r.params
        h = p["cutting.uncut_thickness"]
        assert p["geometry.uncut"] == h
        for key, per_h in (("cutting.cut_length", 8 / 3), ("geometry.length", 12), ("geometry.pre_cut", 2)):
            assert math.isclose(p[key], per_h * h, rel_tol=1e-6), key
        scene = parse(r.data, str(CAMPAIGN))
        assert scene.cutting.edge_size == 1e-5 and scene.loading.steps == 80      # [set]: every run, not a parameter
        assert "cutting.edge_size" not in p
        fe = fe_scene(scene)
        assert math.isclose(fe.contact.path.x[-1], -8 / 3 * h * 1e3, rel_tol=1e-6)


def test_fit_of_a_two_cut_sweep(tmp_path):
    from wendel.cutting import fe_campaign

    sweep = tmp_path / "kienzle.toml"
    sweep.write_text(f'description = "two short cuts"\nscene = "{WORKFLOWS / "cutting-aisi1045.toml"}"\n'
                     'outputs = ["steady_Fc_N"]\n'
                     '[set]\n"loading.steps" = 3         # 1\n"cutting.cut_length" = 1.5e-5   # m\n'
                     '"geometry.length" = 1.2e-3   # m\n'
                     '[zip]\n"cutting.uncut_thickness" = [1.0e-4, 1.5e-4]   # m\n"geometry.uncut" = [1.0e-4, 1.5e-4]   # m\n')
    out = tmp_path / "sweep"
    assert main(["sweep", str(sweep), "--workers", "1", "--out", str(out), "--quiet"]) == 0
    table = list(csv.DictReader(open(out / "sweep.csv")))
    assert len(table) == 2 and all(r["status"] == "done" for r in table)
    for r in table:
        assert float(r["steady_Fc_N"]) > float(r["steady_Ft_N"]) > 0
        assert math.isclose(float(r["steady_window_to_m"]), 1.5e-5, rel_tol=1e-6)
    assert (out / "steady_Fc_N.png").is_file()

    cuts = fe_campaign.points(out)
    assert [c["status"] for c in cuts] == ["ok", "ok"]
    assert sorted(c["h"] for c in cuts) == [1e-4, 1.5e-4] and all(c["Fc_oxley"] > 0 for c in cuts)
    fits = fe_campaign.compare(cuts, "aisi1045")
    fe = [f for f in fits if f["source"] == "FE fit"]
    assert len(fe) == 1 and fe[0]["rows"] == 2
    assert math.isfinite(fe[0]["kc11_N_per_mm2"]) and fe[0]["kc11_N_per_mm2"] > 0 and math.isfinite(fe[0]["mc"])
    # two points: the fit goes through both
    assert fe[0]["max_rel_error"] < 1e-9
    sources = [f["source"] for f in fits]
    assert "Oxley fit" in sources and sum(s.startswith("ISCAR") for s in sources) == 2
    for f in fits[1:]:
        assert math.isclose(f["fe_kc11_difference"], fe[0]["kc11_N_per_mm2"] / f["kc11_N_per_mm2"] - 1)
    png = fe_campaign.plot(tmp_path / "kienzle.png", cuts, fits, "test")
    assert png.stat().st_size > 1000


def test_a_resumed_cut_writes_its_report(tmp_path):
    """A cut killed after its 2nd increment and finished by `wendel run --resume` (as a sweep resumes it) writes
    cutting.csv and the steady figures into summary.json like an uninterrupted one."""
    import json

    from conftest import edit, kill_after_increment

    scene = tmp_path / "cut.toml"
    scene.write_text(edit((WORKFLOWS / "cutting-aisi1045.toml").read_text(), "length = 1.8e-3", "length = 1.2e-3"))
    out = tmp_path / "run"
    kill_after_increment(scene, out, 2)
    rows = list(csv.DictReader(open(out / "cutting.csv")))
    assert len(rows) == 4 and math.isclose(float(rows[-1]["tool_travel_m"]), 20e-6, rel_tol=1e-6)   # smoke: 4 x 5 um
    got = json.loads((out / "summary.json").read_text())["outputs"]
    assert got["steady_Fc_N"] > got["steady_Ft_N"] > 0 and math.isclose(got["steady_window_to_m"], 20e-6, rel_tol=1e-6)
