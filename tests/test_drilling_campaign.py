"""The drilling campaign (workflows/campaigns/drilling-process.toml): feed x speed x eta_w through `wendel sweep`
(real gmsh + FreeFEM, (r, z) at smoke size), its table and pictures of each output against each parameter."""

from __future__ import annotations

import csv
import math

from wendel.cli import main

from conftest import WORKFLOWS

CAMPAIGN = WORKFLOWS / "campaigns" / "drilling-process.toml"
PARAMS = ("drilling.feed", "drilling.speed", "drilling.eta_w")
OUTPUTS = ("peak_T_tc_3mm", "peak_T_tc_8mm", "bore_diameter_error_after_cooling", "bore_diameter_error_end_of_drilling")


def test_drilling_campaign_feed_speed_eta(tmp_path):
    out = tmp_path / "sweep"
    assert main(["sweep", str(CAMPAIGN), "--workers", "2", "--out", str(out), "--quiet"]) == 0
    rows = list(csv.DictReader(open(out / "sweep.csv")))
    assert len(rows) == 8 and all(r["status"] == "done" for r in rows)
    for r in rows:
        for k in OUTPUTS:
            assert math.isfinite(float(r[k])), (k, r)
        assert float(r["energy_balance_error"]) < 0.01
        assert float(r["peak_T_tc_3mm"]) > 293.15
    key = lambda r: tuple(float(r[p]) for p in PARAMS)
    by = {key(r): r for r in rows}
    for (f, n, eta), r in by.items():
        if eta == 0.1:
            hot = by[(f, n, 0.3)]
            # three times the heat into the part: a larger rise at both thermocouples, a wider bore at the end of drilling
            for tc in ("peak_T_tc_3mm", "peak_T_tc_8mm"):
                assert float(hot[tc]) - 293.15 > 2.5 * (float(r[tc]) - 293.15)
            assert float(hot["bore_diameter_error_end_of_drilling"]) > float(r["bore_diameter_error_end_of_drilling"])
    for k in OUTPUTS:
        assert (out / f"{k}.png").is_file()
