"""Benchmark of the updated-Lagrangian kinematics (``wendel bench ul``): the cost of an increment and of a
Newton iteration against small strain on the same mesh and load path."""

from __future__ import annotations

from pathlib import Path

from ..scene import load
from . import WORKFLOWS, register, run_fresh


@register("ul")
def ul_bench(quick: bool, workdir: Path) -> list[dict]:
    """Plane-strain compression (2D) and uniaxial tension of a cube (3D) with linear hardening to 5 % in 5
    increments (small enough for small strain to be a fair comparison), the same cube with the necking bar's
    Voce hardening, and the necking bar (axisymmetric, Voce) to 1 mm in 10, small strain against
    updated-Lagrangian, at growing mesh sizes."""
    cases = [("2d", "ul-compression.toml", h) for h in ([0.04] if quick else [0.04, 0.02, 0.01])]
    cases += [("3d", "ul-tension-3d.toml", h) for h in ([0.25] if quick else [0.25, 0.125])]
    # the cube with a saturating hardening: small strain's path is nonlinear too (with linear hardening it is
    # linear once the body flows, one Newton step per increment, so that row measures the path, not the kinematics)
    cases += [("3d-voce", "ul-tension-3d.toml", h) for h in ([0.25] if quick else [0.125, 0.0625])]
    # the necking bar (axisymmetric, Voce hardening) to 1 mm of elongation in 10 increments: a path on which
    # small strain is nonlinear too (the plastic zone spreads from the imperfection)
    cases += [("axi", "ul-necking-bar.toml", h) for h in ([1e-3] if quick else [1e-3, 0.5e-3])]
    rows = []
    # each case with the accepted state as the first guess of an increment, and with the extrapolated one
    # (numerics.predictor, edp/lib/predictor.idp): small strain and updated-Lagrangian alike
    for (dim, name, h), predictor in ((c, p) for c in cases for p in ("none", "extrapolate")):
        path = WORKFLOWS / name
        row = {"case": dim, "h": h, "predictor": predictor}
        for kind in ("small-strain", "updated-lagrangian"):
            scene = load(path)
            scene.numerics.predictor = predictor
            scene.geometry.h = h
            scene.kinematics.kind = kind
            scene.loading.steps = 5
            if dim == "2d":
                scene.boundary["top"].uy = -0.05
            elif dim.startswith("3d"):
                scene.boundary["top"].uz = 0.05
                if dim == "3d-voce":
                    _necking_bar_steel(scene)
            else:
                scene.loading.steps = 10
                scene.boundary["top"].uy = 0.5e-3
                scene.geometry.params["refine"]["h"] = 0.4 * h
            scene.output.png = False
            scene.output.vtu = False
            out = workdir / f"{dim}-h{h:g}-{kind}-{predictor}"
            s = run_fresh(scene, path, out)
            ph = s["wall_time_by_phase"]
            work = ph["assembly"] + ph["linear_solve"] + ph["constitutive"]
            tag = "ss" if kind == "small-strain" else "ul"
            row.update({"dofs": s["dofs"], f"newton_{tag}": s["newton_iterations"],
                        f"per_increment_{tag}": work / s["increments"],
                        f"per_iteration_{tag}": work / max(s["newton_iterations"], 1)})
        row["increment_cost_ratio"] = row["per_increment_ul"] / row["per_increment_ss"]
        row["iteration_cost_ratio"] = row["per_iteration_ul"] / row["per_iteration_ss"]
        rows.append(row)
    return rows


def _necking_bar_steel(scene) -> None:
    """The necking bar's material (workflows/ul-necking-bar.toml: Simo 1988, E, nu, Voce sigma0, sigma_inf,
    delta and the linear term H) on another scene."""
    bar = load(WORKFLOWS / "ul-necking-bar.toml")
    scene.material.E, scene.material.nu = bar.material.E, bar.material.nu
    scene.plasticity = bar.plasticity.model_copy()
