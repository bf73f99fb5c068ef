"""The ``[plasticity]`` block: small-strain von Mises plasticity (edp/lib/plasticity.idp).

Hardening laws go through a registry of names to the integer ids of ``-plast_law``:

>>> sorted(LAWS.items(), key=lambda kv: kv[1])
[('perfect', 0), ('linear', 1), ('step42', 1), ('johnson-cook', 2), ('voce', 3)]
>>> Plasticity(law="linear", sigma0=250e6, H=1e9).law
'linear'

``step42`` is deal.II step-42's convention: the yield test is on the Frobenius norm of the deviatoric
stress, ``|dev sigma| <= sigma0``, and the hardening parameter ``gamma`` scales the excess of the trial
stress, ``|s| = sigma0 + gamma (|s_trial| - sigma0)``. That is linear isotropic hardening in the von
Mises form with ``sigma_y0 = sqrt(3/2) sigma0`` and ``H = 3 mu gamma / (1 - gamma)`` (modulus
``2 mu gamma / (1 - gamma)`` in the Frobenius norm), exactly, for one load step from a virgin state:

>>> sy0, H = step42_to_von_mises(400.0, 0.01, E=200000.0, nu=0.3)
>>> round(sy0, 4), round(H, 4)
(489.8979, 2331.0023)
"""

from __future__ import annotations

import math
from typing import Optional

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from . import Block, register

LAWS = {"perfect": 0, "linear": 1, "johnson-cook": 2, "step42": 1, "voce": 3}
"""Hardening law name -> ``-plast_law`` id of plasticity.idp (``step42`` is ``linear`` in step-42's units)."""


def step42_to_von_mises(sigma0: float, gamma: float, E: float, nu: float) -> tuple[float, float]:
    """Von Mises yield stress and linear hardening modulus of step-42's (sigma0, gamma) [Pa, Pa]."""
    mu = E / (2.0 * (1.0 + nu))
    return math.sqrt(1.5) * sigma0, 3.0 * mu * gamma / (1.0 - gamma)


class Plasticity(BaseModel):
    """Von Mises plasticity: perfect, linear isotropic hardening, Johnson-Cook or Voce (saturation plus linear:
    sigma_y = sigma0 + H p + (voce_sigma_inf - sigma0)(1 - exp(-voce_delta p)))."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    law: str = Field("perfect", description=f"hardening law: {', '.join(LAWS)}")
    sigma0: Optional[float] = Field(None, gt=0, description="initial yield stress, perfect, linear and voce (von Mises); step42: of |dev sigma| [Pa]")
    gamma: float = Field(0.0, ge=0, lt=1, description="step42 law: hardening parameter of deal.II step-42 [1]")
    H: float = Field(0.0, ge=0, description="linear isotropic hardening modulus d sigma_y / d p (linear; the linear term of voce) [Pa]")
    voce_sigma_inf: Optional[float] = Field(None, gt=0, description="voce law: saturation stress sigma_inf of the exponential term, >= sigma0 [Pa]")
    voce_delta: float = Field(0.0, ge=0, description="voce law: saturation exponent delta, (sigma_inf - sigma0)(1 - exp(-delta p)) [1]")
    jc_A: Optional[float] = Field(None, gt=0, description="Johnson-Cook yield stress A [Pa]")
    jc_B: float = Field(0.0, ge=0, description="Johnson-Cook hardening modulus B [Pa]")
    jc_n: float = Field(1.0, gt=0, description="Johnson-Cook hardening exponent n [1]")
    jc_C: float = Field(0.0, ge=0, description="Johnson-Cook strain-rate sensitivity C [1]")
    jc_rate0: float = Field(1.0, gt=0, description="Johnson-Cook reference strain rate [1/s]")
    jc_m: float = Field(1.0, gt=0, description="Johnson-Cook thermal softening exponent m [1]")
    jc_T_room: float = Field(293.15, gt=0, description="Johnson-Cook reference temperature T_R [K]")
    jc_T_melt: float = Field(1793.0, gt=0, description="Johnson-Cook melting temperature T_M [K]")
    temperature: Optional[float] = Field(None, gt=0, description="uniform temperature without a thermal block [K]; default T_R")
    load_time: float = Field(0.0, ge=0, description="time per unit load factor, sets the strain rate [s]; 0 = quasi-static")
    limit_ratio: float = Field(1e-3, gt=0, lt=1, description="tangent/elastic stiffness ratio below which a failed increment of a perfectly plastic body is a limit load [1]")
    reference: Optional[str] = Field(None, description="closed-form reference: hill (thick-walled cylinder under "
                                     "internal pressure, perfect law, ring builder, pressure on inner): plastic radius")

    @field_validator("law")
    @classmethod
    def _known_law(cls, v):
        if v not in LAWS:
            raise ValueError(f"unknown plasticity law {v!r}; valid: {', '.join(LAWS)}")
        return v

    @model_validator(mode="after")
    def _parameters(self):
        if self.reference not in (None, "hill"):
            raise ValueError(f"unknown plasticity reference {self.reference!r}; valid: hill")
        if self.law in ("perfect", "linear", "step42", "voce") and self.sigma0 is None:
            raise ValueError(f"plasticity.law = {self.law!r} needs sigma0")
        if self.law == "voce" and (self.voce_sigma_inf is None or self.voce_sigma_inf < self.sigma0):
            raise ValueError("plasticity.law = 'voce' needs voce_sigma_inf >= sigma0")
        if self.law == "johnson-cook":
            if self.jc_A is None:
                raise ValueError("plasticity.law = 'johnson-cook' needs jc_A")
            if not self.jc_T_melt > self.jc_T_room:
                raise ValueError("plasticity.jc_T_melt must be above jc_T_room")
        return self


def options(block: Plasticity, scene, files) -> list[str]:
    """``-plast_*`` options of plasticity.idp (numbers and the law id only)."""
    H, sigma0 = block.H, block.sigma0
    if block.law == "step42":
        sigma0, H = step42_to_von_mises(block.sigma0, block.gamma, scene.material.E, scene.material.nu)
    opts = ["-plast_law", str(LAWS[block.law]), "-plast_H", repr(H),
            "-plast_jc_B", repr(block.jc_B), "-plast_jc_n", repr(block.jc_n), "-plast_jc_C", repr(block.jc_C),
            "-plast_jc_rate0", repr(block.jc_rate0), "-plast_jc_m", repr(block.jc_m),
            "-plast_jc_Tr", repr(block.jc_T_room), "-plast_jc_Tm", repr(block.jc_T_melt),
            "-plast_load_time", repr(block.load_time), "-plast_limit_ratio", repr(block.limit_ratio)]
    if sigma0 is not None:
        opts += ["-plast_sigma0", repr(sigma0)]
    if block.jc_A is not None:
        opts += ["-plast_jc_A", repr(block.jc_A)]
    if block.law == "voce":
        opts += ["-plast_voce_sinf", repr(block.voce_sigma_inf), "-plast_voce_delta", repr(block.voce_delta)]
    if block.temperature is not None:
        opts += ["-plast_T", repr(block.temperature)]
    if block.reference == "hill":
        opts += hill_options(block, scene)
    return opts


def hill_options(block: Plasticity, scene) -> list[str]:
    """``-plast_hill_*`` options: Hill's cylinder (pressure at load factor 1, inner and outer radii)."""
    g, inner = scene.geometry, scene.boundary.get("inner")
    if block.law != "perfect" or g.builder != "ring" or inner is None or not inner.pressure:
        raise ValueError("plasticity.reference = 'hill' needs law = 'perfect', geometry.builder = 'ring' and "
                         "a pressure on boundary.inner")
    p = g.params
    return ["-plast_hill_q", repr(float(inner.pressure)), "-plast_hill_a", repr(float(p.get("r_inner", 1.0))),
            "-plast_hill_b", repr(float(p.get("r_outer", 1.3)))]


register(Block(name="plasticity", model=Plasticity, options=options, macro="WITHPLASTICITY",
               fields=("p", "sigma_y", "plastic", "epsp_xx", "epsp_yy", "epsp_zz", "epsp_xy")))
