"""The Dirichlet rows of the Newton system hold the prescribed total displacement, also on a remeshed body.

Since session 11 ``lib/mechanics.idp`` computes the Dirichlet gap lf g - ub - u of a residual by array
operations: the boundary form at u = 0 once per increment (the prescribed value less the displacement reached
before the current mesh, ``-ubase``), less u on the fixed rows. Upsetting at smoke size (8 increments, three
remeshes, each later segment starting from its ubase): at every accepted increment the nodes of both platens
must carry exactly the prescribed total displacement (the top platen moves down by 0.5 lf, both stick).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np

from wendel.meshes import LABELS
from wendel.results.vtu import read_array

ROOT = Path(__file__).resolve().parents[1]


def _platen_nodes(mesh_file: Path, name: str) -> np.ndarray:
    m = meshio.read(mesh_file)
    nodes = [c.data[m.cell_data["gmsh:physical"][k] == LABELS[name]].ravel()
             for k, c in enumerate(m.cells) if c.type == "line"]
    return np.unique(np.concatenate(nodes))


def test_prescribed_total_displacement_after_remeshes(tmp_path):
    out = tmp_path / "ups"
    subprocess.run([sys.executable, "-m", "wendel.cli", "run", str(ROOT / "workflows" / "upsetting.toml"), "--smoke",
                    "--out", str(out)], check=True, capture_output=True, cwd=ROOT)
    state = json.loads((out / "checkpoint.json").read_text())
    segments = state["segments"]
    assert len(segments) >= 3 and all(s["ubase"] for s in segments[1:])      # remeshed: later launches have a ubase
    checked = 0
    for inc, lf in state["accepted"]:
        seg = max((s for s in segments if s["first"] <= inc), key=lambda s: s["first"])
        d = out / "fem" / f"inc-{inc:04d}"
        field = d / ("u_total.node.txt" if seg["ubase"] else "u.node.txt")
        u = read_array(field).reshape(-1, 2)
        top, bottom = (_platen_nodes(out / seg["mesh"], n) for n in ("top", "bottom"))
        assert len(top) > 2 and len(bottom) > 2
        np.testing.assert_allclose(u[top], np.tile([0.0, -0.5 * lf], (len(top), 1)), rtol=0, atol=1e-12)
        np.testing.assert_allclose(u[bottom], 0.0, rtol=0, atol=1e-12)
        checked += 1
    assert checked == len(state["accepted"]) >= 8
