"""The thermo-mechanical indentation: contact, Johnson-Cook plasticity and heat in one Newton loop."""

import json

import meshio
import numpy as np

from wendel.results import vtu as output
from wendel.loop import run

from conftest import WORKFLOWS


def test_heated_ball_indents_a_jc_block(tmp_path):
    root = run(WORKFLOWS / "thermo-indent.toml", smoke=True, out=tmp_path / "r", png=False, progress=lambda *_: None)
    s = json.loads((root / "summary.json").read_text())
    assert s["completed"] and s["blocks"] == ["contact", "plasticity", "thermal"]
    steps = output.read_pvd(root / "results.pvd")
    assert len(steps) == s["increments"] >= 2
    forces, tmax = [], []
    for t, vtu in steps:
        m = meshio.read(vtu)
        for name in ("u", "T", "contact_pressure"):
            assert name in m.point_data, name
        assert "p" in m.cell_data
        rec = json.loads((root / "fem" / vtu.stem / "record.json").read_text())
        forces.append(rec["contact_force"])
        tmax.append(rec["max_temperature"])
        assert abs(rec["energy_balance_error"]) < 0.01           # energy balance within 1%
        assert np.isfinite(m.point_data["T"]).all()
    last = s["last_increment"]
    assert forces[-1] > forces[0] > 0                           # the ball pushes harder as it goes in
    assert 293.15 < tmax[-1] < 800.0                            # heated by the tool, below the tool temperature
    assert last["max_plastic_strain"] > 0 and last["heat_plastic"] > 0
