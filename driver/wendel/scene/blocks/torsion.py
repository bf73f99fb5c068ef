"""The scalar problem ``torsion``: elastic-plastic torsion of a prismatic bar (table ``[torsion]``).

Prandtl's stress function phi (Pa m) of the cross-section solves -Laplace(phi) = 2 mu theta, phi = 0 on
the boundary, |grad phi| <= tau_y; for a simply connected section this is the obstacle problem
phi <= tau_y dist(x, boundary), solved by the PDAS of the membrane obstacle problem (``edp/obstacle.edp``,
``-obst_id 3``). The twist theta is scaled by the load factor; the torque is T = 2 int(phi).

With ``reference = "circular"`` (needs the ``disk`` builder) the closed forms of a circular bar of radius
R are the reference: elastic core c = tau_y / (mu theta), T = (2 pi / 3) tau_y R^3 (1 - (c/R)^3 / 4)
past the elastic limit theta_e = tau_y / (mu R), T = (pi / 2) mu theta R^4 below it.

>>> Torsion(mu=80e9, tau_y=200e6, theta=1.0).reference is None
True
>>> round(circular_torque(1.0, mu=80e9, tau_y=200e6, radius=0.01), 6)   # N m, c/R = 1/4
417.242774
"""

from __future__ import annotations

import math
from typing import Optional

from pydantic import BaseModel, ConfigDict, Field, field_validator

from . import Block, Problem, register, register_problem

REFERENCES = ("circular",)


class Torsion(BaseModel):
    """A bar twisted by theta per unit length; elastic-perfectly plastic (shear yield stress tau_y)."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    mu: float = Field(..., gt=0, description="shear modulus [Pa]")
    tau_y: float = Field(..., gt=0, description="shear yield stress [Pa] (von Mises: sigma_y / sqrt(3))")
    theta: float = Field(..., gt=0, description="twist per unit length at load factor 1 [rad/m]")
    c: float = Field(100.0, gt=0, description="active-set constant [1/m^2]; the solution does not depend on it")
    reference: Optional[str] = Field(None, description="closed-form reference: circular (disk builder: torque, "
                                     "elastic core radius, phi)")

    @field_validator("reference")
    @classmethod
    def _reference(cls, v):
        if v is not None and v not in REFERENCES:
            raise ValueError(f"unknown torsion reference {v!r}; valid: {', '.join(REFERENCES)}")
        return v


def circular_torque(theta: float, mu: float, tau_y: float, radius: float) -> float:
    """Torque (N m) of an elastic-perfectly plastic circular bar twisted by ``theta`` (rad/m)."""
    c = tau_y / (mu * theta) if theta > 0 else math.inf
    if c >= radius:
        return math.pi / 2 * mu * theta * radius ** 4
    return 2 * math.pi / 3 * tau_y * radius ** 3 * (1 - 0.25 * (c / radius) ** 3)


def _entry(scene, dimension: int) -> str:
    if dimension != 2:
        raise ValueError("problem 'torsion' is 2D (the bar's cross-section)")
    return "obstacle.edp"


def _options(scene, files, dimension: int) -> list[str]:
    t = scene.torsion
    if t is None:
        raise ValueError("problem 'torsion' needs a [torsion] table")
    opts = ["-obst_id", "3", "-obst_c", repr(t.c), "-tors_mu", repr(t.mu), "-tors_tauy", repr(t.tau_y),
            "-tors_theta", repr(t.theta)]
    if t.reference == "circular":
        g = scene.geometry
        if g.builder != "disk":
            raise ValueError("torsion.reference = 'circular' needs geometry.builder = 'disk'")
        params = g.params
        center = list(params.get("center", (0.0, 0.0)))
        opts += ["-tors_R", repr(float(params.get("radius", 1.0))), "-tors_cx", repr(float(center[0])),
                 "-tors_cy", repr(float(center[1]))]
    return opts


register(Block(name="torsion", model=Torsion, options=lambda *_: [], mechanics=False,
               fields=("u", "phi", "tau", "lambda", "active", "gap")))
register_problem(Problem(name="torsion", entry=_entry, options=_options, tables=("torsion",)))
