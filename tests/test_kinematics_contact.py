"""Contact in updated-Lagrangian scenes: the gap and normal are measured in the current configuration
(edp/lib/friction.idp with law none for a frictionless plane or ball obstacle), not on the launch mesh."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from wendel.loop import run
from wendel.results import vtu as output

SCENE = """description = "a block slid 0.5 m under a rigid cylinder that presses it: updated-Lagrangian, frictionless"

[geometry]
builder = "rectangle"
x = [-2.0, 2.0]          # m
y = [-1.0, 0.0]          # m
h = 0.2                  # m
refine = { box = [[-1.0, -0.2], [0.5, 0.0]], thickness = 0.2, h = 0.04 }   # m, where the contact will be

[material]
E = 1.0e9                # Pa
nu = 0.3                 # 1

[kinematics]
kind = "KIND"

[boundary.bottom]
ux = -0.5                # m: the block translates 0.5 m to the left
uy = 0.0                 # m

[contact]
boundary = "top"
normal = "+y"
obstacle = "ball"        # a disc: the cylinder's section
center = [0.0, 1.0]      # m, fixed in space above x = 0
radius = 1.0             # m
displacement = -0.01     # m, pressed 10 mm

[loading]
steps = 4

[numerics]
solver = "direct"
newton_tol = 1e-9
newton_maxit = 40

[output]
png = false
"""


def peak(root: Path) -> tuple[float, float]:
    """(current x, material x on the launch mesh) of the node with the largest contact pressure (m)."""
    d = sorted((root / "fem").glob("inc-*"))[-1]
    pos = output.read_array(d / "position.node.txt").reshape(-1, 2)
    X = pos - output.read_array(d / "u_total.node.txt").reshape(-1, 2)
    i = int(np.argmax(output.read_array(d / "contact_pressure.node.txt")))
    return float(pos[i, 0]), float(X[i, 0])


def test_the_contact_gap_is_measured_in_the_current_configuration(scene_file, tmp_path, quiet):
    """The block slides 0.5 m to the left under a fixed cylinder: the pressure peaks under the cylinder
    (current x = 0, material x = 0.5) within an element; on the launch mesh's gap it would peak at the material
    point first under the cylinder (current x = -0.5)."""
    root = run(scene_file(SCENE.replace("KIND", "updated-lagrangian"), "b.toml"), out=tmp_path / "b",
               progress=quiet, png=False)
    x, X = peak(root)
    assert abs(x) < 0.04 and abs(X - 0.5) < 0.04, (x, X)
