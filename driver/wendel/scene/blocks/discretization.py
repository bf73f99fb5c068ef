"""The ``[discretization]`` block: continuous (default) or discontinuous Galerkin displacements (edp/lib/dg.idp).

``kind = "dg"`` launches ``edp/mechanics.edp`` with ``-DWITHDG=1 -DPk=P1dc`` (or ``P2dc``): symmetric interior
penalty with Nitsche Dirichlet boundaries, the penalty ``gamma_mu`` on the jump and ``gamma_lambda`` on the normal
jump. The sufficient stability bound of both penalties (dg.idp's header) is ``2 (d + 1) k (k + d - 1) / d``:

>>> gamma_min(1, 2), gamma_min(2, 2), round(gamma_min(2, 3), 2)
(6.0, 18.0, 21.33)
>>> penalty_warnings(Discretization(kind="dg", order=2, gamma_mu=10.0), 2)
['discretization.gamma_mu = 10.0 is below the sufficient stability bound 18 of P2 DG in 2D (dg.idp): the discrete problem may not be coercive']
"""

from __future__ import annotations

import math
from typing import Literal, Optional

from pydantic import BaseModel, ConfigDict, Field, field_validator

from . import Block, register


def gamma_min(order: int, dimension: int) -> float:
    """Sufficient penalty for coercivity: 2 (d + 1) C_k, C_k = k (k + d - 1) / d (Warburton-Hesthaven) [1]."""
    return 2.0 * (dimension + 1) * order * (order + dimension - 1) / dimension


class Discretization(BaseModel):
    """Continuous Lagrange (cg) or symmetric interior penalty discontinuous Galerkin (dg) displacements."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    kind: Literal["cg", "dg"] = Field("cg", description="cg: continuous Lagrange (elasticity.order); dg: "
                                      "interior penalty with Nitsche boundaries (2D, 3D; elastic or J2 plastic)")
    order: int = Field(1, ge=1, le=2, description="polynomial degree of the DG displacement (P1dc, P2dc) [1]")
    gamma_mu: float = Field(20.0, gt=0, le=1e6, description="penalty on the jump, times 2 mu |F|/|K| [1]; "
                            "sufficient: 6 (P1), 18 (P2) in 2D, 8 and 21.3 in 3D")
    gamma_lambda: float = Field(20.0, gt=0, le=1e6, description="penalty on the normal jump, times lambda "
                                "|F|/|K| [1]; same bound")
    separation_stress: float = Field(0.0, ge=0, le=1e15, description="dg: an interior face whose normal stress "
                                     "(mean of its two elements) exceeds this opens for good [Pa]; 0 = never")
    after_separation: Literal["dg", "cg"] = Field("dg", description="dg with separation_stress in 2D: 'cg' goes "
                                                  "on with CG on the remeshed bodies once the opened faces cut "
                                                  "the body into two or more (boundary 'opened', free)")
    region: Optional[list[list[float]]] = Field(None, description="dg in 2D: only the cells whose centre lies in "
                                                "this box [[x0, y0], [x1, y1]] are DG, the others CG, coupled by "
                                                "Nitsche terms (elastic) [m]")

    @field_validator("region")
    @classmethod
    def _region(cls, v):
        if v is None:
            return v
        if len(v) != 2 or any(len(c) != 2 for c in v):
            raise ValueError("region must be [[x0, y0], [x1, y1]] (m)")
        if any(not math.isfinite(c) or abs(c) > 1e30 for p in v for c in p):
            raise ValueError(f"region: coordinates must be finite numbers below 1e30 in size, got {v}")
        if not (v[0][0] < v[1][0] and v[0][1] < v[1][1]):
            raise ValueError(f"region: the corners must increase, [[x0, y0], [x1, y1]] with x0 < x1, y0 < y1; got {v}")
        return v


def penalty_warnings(block: Discretization, dimension: int) -> list[str]:
    """Messages for penalties below the sufficient bound (the run goes on: the bound is not sharp)."""
    if block.kind != "dg":
        return []
    low = gamma_min(block.order, dimension)
    return [f"discretization.{key} = {getattr(block, key)} is below the sufficient stability bound {low:g} of "
            f"P{block.order} DG in {dimension}D (dg.idp): the discrete problem may not be coercive"
            for key in ("gamma_mu", "gamma_lambda") if getattr(block, key) < low]


def check(block: Discretization, scene) -> None:
    """DG joins plasticity (P1 and P2); plane 2D or 3D (3D: no separation, no region); direct solver, no remesh,
    no prescribed motion."""
    if block.kind != "dg":
        if block.separation_stress > 0:
            raise ValueError("discretization.separation_stress needs discretization.kind = 'dg'")
        if block.region is not None:
            raise ValueError("discretization.region needs discretization.kind = 'dg'")
        if block.after_separation != "dg":
            raise ValueError("discretization.after_separation needs discretization.kind = 'dg'")
        return
    if block.after_separation == "cg" and (block.separation_stress <= 0 or getattr(scene, "plasticity", None)):
        raise ValueError("discretization.after_separation = 'cg' needs separation_stress > 0 and an elastic scene "
                         "(the plastic state is not carried from DG to CG)")
    if block.region is not None and (getattr(scene, "plasticity", None) is not None or block.separation_stress > 0):
        raise ValueError("discretization.region (CG and DG in one mesh) is elastic only, without separation_stress")
    others = [n for n in scene.blocks if n not in ("discretization", "plasticity")]
    if others:
        raise ValueError(f"discretization.kind = 'dg' is implemented for elastic and plastic scenes only; "
                         f"remove [{others[0]}]")
    g = scene.geometry
    if (g.builder == "box" or g.dimension == 3) and (block.separation_stress > 0 or block.region is not None):
        raise ValueError("discretization.kind = 'dg' in 3D has no separation_stress and no region: FreeFEM 4.9 "
                         "assembles 3D face terms as matrices only (dg3d.idp)")
    if scene.elasticity.plane == "axisymmetric" or scene.elasticity.order != 1:
        raise ValueError("discretization.kind = 'dg' needs elasticity.plane = 'strain' or 'stress' and "
                         "elasticity.order = 1 (the DG degree is discretization.order)")
    if scene.remesh is not None or scene.kinematics.updated_lagrangian:
        raise ValueError("discretization.kind = 'dg' does not remesh and is small strain")
    if scene.numerics.solver != "direct":
        raise ValueError("discretization.kind = 'dg' needs numerics.solver = 'direct'")
    moving = [name for name, b in scene.boundary.items() if b.motion]
    if moving:
        raise ValueError(f"boundary.{moving[0]}: a prescribed motion is not implemented with discretization.kind = 'dg'")


def options(block: Discretization, scene, files) -> list[str]:
    """``-dg_*`` options of dg.idp (numbers only); nothing for cg."""
    if block.kind != "dg":
        return []
    return ["-dg_gamma_mu", repr(block.gamma_mu), "-dg_gamma_lambda", repr(block.gamma_lambda),
            "-dg_order", str(block.order), "-dg_sep_stress", repr(block.separation_stress)] + \
        ([] if block.region is None else ["-dg_region_x0", repr(block.region[0][0]), "-dg_region_y0",
                                          repr(block.region[0][1]), "-dg_region_x1", repr(block.region[1][0]),
                                          "-dg_region_y1", repr(block.region[1][1])])


def macros(scene) -> list[str]:
    """``-DWITHDG=1`` for ``kind = "dg"`` (the element ``-DPk=P1dc|P2dc`` comes from :func:`element`)."""
    block = getattr(scene, "discretization", None)
    return ["-DWITHDG=1"] if block is not None and block.kind == "dg" else []


def element(scene) -> str | None:
    """``P1dc``/``P2dc`` for a DG scene, else None."""
    block = getattr(scene, "discretization", None)
    return f"P{block.order}dc" if block is not None and block.kind == "dg" else None


register(Block(name="discretization", model=Discretization, options=options, check=check, macro=None))
