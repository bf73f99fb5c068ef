"""Updated-Lagrangian kinematics in axisymmetric (r, z) models (edp/lib/kinematics-axi.idp): the hoop stretch
r / R enters the deformation gradient.

The compression of a cylinder between frictionless platens is homogeneous, so any mesh is exact and the
reference is the closed form of uniaxial compression with linear hardening.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from wendel.loop import run
from wendel.results import vtu as output

from conftest import WORKFLOWS


def increments(root: Path):
    """(record, cell fields, current vertex positions) of every increment of a run, in order."""
    out = []
    for d in sorted((root / "fem").glob("inc-*")):
        rec = json.loads((d / "record.json").read_text())
        cells = {f.name.removesuffix(".cell.txt"): output.read_array(f) for f in d.glob("*.cell.txt")}
        out.append((rec, cells, output.read_array(d / "position.node.txt").reshape(-1, 2)))
    return out


def test_frictionless_compression_of_a_cylinder_to_half_height(scene_file, tmp_path, quiet):
    """50 % height in 10 increments: log strain ln(h / h0) axially and ln(r / r0) / -2 radially and in hoop
    (1e-12); Cauchy stress on sigma = sigma0 + E H / (E + H) (|eps| - sigma0 / E) (1e-10); radial and hoop
    stresses 0; the platen force equals sigma_y(eps) times the current area pi r^2 (1e-10)."""
    E, H, s0 = 70e9, 1e9, 250e6
    text = (WORKFLOWS / "ul-compression-axi.toml").read_text()
    root = run(scene_file(text, "c.toml"), smoke=True, out=tmp_path / "c", progress=quiet, png=False)
    incs = increments(root)
    assert len(incs) == 10
    for rec, cells, pos in incs:
        e = math.log(1 - 0.5 * rec["load_factor"])
        ref = -(s0 + E * H / (E + H) * (abs(e) - s0 / E))
        r = pos[:, 0].max()
        assert np.abs(cells["strain_yy"] - e).max() < 1e-12
        assert np.abs(cells["strain_hoop"] - math.log(r)).max() < 1e-12         # r0 = 1 m
        assert np.abs(cells["strain_xx"] - math.log(r)).max() < 1e-12
        assert np.abs(cells["stress_yy"] / ref - 1).max() < 1e-10, (rec["increment"], cells["stress_yy"].mean(), ref)
        for k in ("stress_xx", "stress_zz", "stress_xy"):              # radial, hoop, shear
            assert np.abs(cells[k]).max() < 1e-10 * abs(ref)
        assert abs(rec["reaction_y_4"] / (ref * math.pi * r ** 2) - 1) < 1e-10
    assert abs(np.ptp(incs[-1][2][:, 1]) - 0.5) < 1e-12 and incs[-1][2][:, 0].max() > 1.41       # h = h0 / 2, r ~ sqrt 2
