"""Benchmark ``friction``: Newton iterations and wall time of frictional contact against the frictionless
solve of the same scene (``wendel bench friction``; ``--quick``: smoke sizes).

Scenes: the Hertz cylinder (workflows/hertz.toml: frictionless by contact.idp's axis gap, frictionless and
Coulomb mu = 0.3 by friction.idp in the current configuration), the sliding block
(workflows/sliding-block.toml: frictionless, Coulomb mu = 0.3, Tresca 3e4 Pa), the 3D sliding block
(frictionless, Coulomb mu = 0.3) and the STL sphere (workflows/stl-ball.toml) against the analytic ball
(the cost of the closest point on the triangles).
"""

from __future__ import annotations

from pathlib import Path

from . import register, run_fresh
from ..scene.blocks.contact import Friction

ROOT = Path(__file__).resolve().parents[3]

CASES = [
    ("hertz", "frictionless, axis gap (contact.idp)", None),
    ("hertz", "frictionless, current configuration (friction.idp)", {"law": "none"}),
    ("hertz", "Coulomb mu = 0.3 (friction.idp)", {"law": "coulomb", "mu": 0.3}),
    ("sliding-block", "frictionless (friction.idp)", {"law": "none"}),
    ("sliding-block", "Coulomb mu = 0.3 (friction.idp)", {"law": "coulomb", "mu": 0.3}),
    ("sliding-block", "Tresca 3e4 Pa (friction.idp)", {"law": "tresca", "tau_max": 3.0e4}),
    ("sliding-block-3d", "frictionless (friction.idp)", {"law": "none"}),
    ("sliding-block-3d", "Coulomb mu = 0.3 (friction.idp)", {"law": "coulomb", "mu": 0.3}),
    ("stl-ball", "analytic ball, frictionless (friction.idp)", "ball"),
    ("stl-ball", "STL sphere, frictionless (friction.idp)", None),
]


@register("friction")
def bench_friction(quick: bool, workdir: Path) -> list[dict]:
    """One row per (scene, variant): increments, Newton iterations, wall time and their ratios to the first
    (frictionless) variant of the scene."""
    from ..scene import load

    rows, base = [], {}
    for k, (name, variant, friction) in enumerate(CASES):
        path = ROOT / "workflows" / f"{name}.toml"
        scene = load(path, smoke=quick)
        scene.output.png = False
        if friction == "ball":          # the analytic sphere the STL file approximates, through the same module
            scene.contact = scene.contact.model_copy(update={"obstacle": "ball", "tool": None,
                                                              "friction": Friction(law="none")})
        elif friction is not None:
            scene.contact.friction = Friction(**friction)
        out = workdir / f"{k}-{name}"
        s = run_fresh(scene, path, out, smoke=quick)
        last = s["last_increment"]
        row = {"scene": name, "variant": variant, "dofs": s["dofs"], "increments": s["increments"],
               "newton_iterations": s["newton_iterations"], "wall_time": round(s["wall_time"], 3),
               "contact_force": last.get("contact_force"), "friction_ratio": last.get("friction_ratio"),
               "error_contact_size": last.get("error_contact_size")}
        base.setdefault(name, row)
        row["iterations_vs_frictionless"] = round(row["newton_iterations"] / base[name]["newton_iterations"], 3)
        row["time_vs_frictionless"] = round(row["wall_time"] / base[name]["wall_time"], 3)
        rows.append(row)
    return rows
