"""The ``[thermal]`` block: heat conduction coupled to the mechanics (edp/lib/thermal.idp).

Heat equation ``rho c dT/dt + dimK alpha T_ref div(du/dt) - div(k grad T) = r + beta sigma_y dp/dt``
(backward Euler over the increments, time ``t = load factor * duration``; steady when ``duration = 0``),
thermal strain ``alpha (T - T_ref) I`` in the stress. Couplings go through a registry of names to the
integer ids of ``-therm_coupling``; boundary kinds to the row kinds of the ``-therm_bc`` table:

>>> sorted(COUPLINGS.items(), key=lambda kv: kv[1])
[('monolithic', 0), ('staggered', 1), ('adiabatic', 2)]
>>> ThermalBoundary(h=10.0, T_inf=300.0).row()
(2, 10.0, 300.0)
>>> Thermal(k=1.0, rho=1.0, c=1.0, alpha=0.0, boundary={"left": {"temperature": 300.0}}).coupling
'monolithic'
"""

from __future__ import annotations

from typing import Literal, Optional, Union

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from . import Block, choice, register
from ...meshes import LABELS

COUPLINGS = {"monolithic": 0, "staggered": 1, "adiabatic": 2}
CouplingName = choice(COUPLINGS, "coupling")
"""Coupling name -> ``-therm_coupling`` id of thermal.idp."""
SOURCES = {"none": 0, "uniform": 1, "manufactured": 2, "moving": 3}
"""Heat source kind -> ``-therm_source_id`` id of thermal.idp."""


class ThermalBoundary(BaseModel):
    """One condition on a named boundary: a temperature, an inward heat flux, or convection."""

    model_config = ConfigDict(extra="forbid")

    temperature: Optional[float] = Field(None, gt=0, description="prescribed temperature [K]")
    flux: Optional[float] = Field(None, description="heat flux into the body [W/m^2]")
    h: Optional[float] = Field(None, ge=0, description="convection coefficient [W/m^2/K]")
    T_inf: Optional[float] = Field(None, gt=0, description="ambient temperature of the convection [K]")

    @model_validator(mode="after")
    def _one_kind(self):
        kinds = [self.temperature is not None, self.flux is not None, self.h is not None or self.T_inf is not None]
        if sum(kinds) != 1:
            raise ValueError("give exactly one of: temperature, flux, or h with T_inf")
        if kinds[2] and (self.h is None or self.T_inf is None):
            raise ValueError("convection needs both h and T_inf")
        return self

    def row(self) -> tuple[int, float, float]:
        """(kind, a, b) of thermal.idp's boundary table."""
        if self.temperature is not None:
            return 0, self.temperature, 0.0
        if self.flux is not None:
            return 1, self.flux, 0.0
        return 2, self.h, self.T_inf


class MovingSource(BaseModel):
    """A heat source moving at constant velocity: a Gaussian ``Q exp(-|x - c(t)|^2 / s^2) / (pi^(d/2) s^d)``,
    ``c(t) = start + velocity t`` (d = 2 in a plane 2D model, 3 in 3D and on the axis of an (r, z) model)."""

    model_config = ConfigDict(extra="forbid")

    power: float = Field(..., gt=0, description="power of the source [W] (W/m in a plane 2D model)")
    radius: float = Field(..., gt=0, description="Gaussian radius s of the source [m]")
    start: list[float] = Field(..., min_length=2, max_length=3, description="centre at t = 0 (x, y[, z]) [m]")
    velocity: list[float] = Field(..., min_length=2, max_length=3, description="velocity (vx, vy[, vz]) [m/s]")


class Thermal(BaseModel):
    """Heat conduction with thermal expansion, Gough-Joule coupling and plastic (Taylor-Quinney) heating."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    k: float = Field(..., gt=0, description="thermal conductivity [W/m/K]")
    rho: float = Field(..., gt=0, description="density [kg/m^3]")
    c: float = Field(..., gt=0, description="specific heat capacity [J/kg/K]")
    alpha: float = Field(..., ge=0, description="linear thermal expansion coefficient [1/K]")
    T_ref: float = Field(293.15, gt=0, description="reference temperature of the thermal strain [K]")
    T_initial: Optional[float] = Field(None, gt=0, description="initial uniform temperature [K]; default T_ref")
    boundary: dict[str, ThermalBoundary] = Field(default_factory=dict, description="thermal conditions by boundary name (unnamed boundaries are insulated)")
    source: Union[float, Literal["manufactured"]] = Field(0.0, description="volumetric heat source [W/m^3], or \"manufactured\" (with reference.analytic = \"manufactured-sine\")")
    beta: float = Field(0.9, ge=0, le=1, description="Taylor-Quinney fraction of plastic work turned into heat [1]")
    coupling: CouplingName = Field("monolithic", description=f"solution of the coupled problem: {', '.join(COUPLINGS)}")
    duration: float = Field(0.0, ge=0, description="process time at load factor 1: an increment lasts (lf - lf_old) * duration [s]; 0 = steady heat equation")
    mms_amplitude: float = Field(1.0, description="amplitude of the manufactured temperature T_ref + lf A phi [K]")
    tool_temperature: Optional[float] = Field(None, gt=0, description="temperature of the contact tool [K]; default T_ref")
    contact_conductance: float = Field(0.0, ge=0, description="heat transfer coefficient through the active contact zone [W/m^2/K]")
    moving_source: Optional[MovingSource] = Field(None, description="a heat source moving at constant velocity ([thermal.moving_source])")
    staggered_softening: bool = Field(True, description="staggered coupling with Johnson-Cook: the mechanical step takes the softening of the heat step's temperature change (block Gauss-Seidel); false: the temperature of the last iterate (slower Newton)")


    @field_validator("boundary")
    @classmethod
    def _boundary(cls, v):
        unknown = [name for name in v if name not in LABELS]
        if unknown:
            raise ValueError(f"unknown boundary {', '.join(unknown)}; valid: {', '.join(LABELS)}")
        return v

    @model_validator(mode="after")
    def _steady(self):
        if self.coupling != "adiabatic" and self.duration == 0 and not any(
                b.temperature is not None or b.h is not None for b in self.boundary.values()):
            raise ValueError(f"a steady heat equation (duration = 0, coupling = {self.coupling!r}) needs a "
                             f"temperature or convection boundary")
        return self

    @property
    def source_kind(self) -> str:
        if self.moving_source is not None:
            return "moving"
        if self.source == "manufactured":
            return "manufactured"
        return "uniform" if self.source != 0 else "none"


def options(block: Thermal, scene, files) -> list[str]:
    """``-therm_*`` options of thermal.idp; the boundary table goes to ``tables/thermal_bc.txt``."""
    if block.coupling == "adiabatic" and getattr(scene, "plasticity", None) is None:
        raise ValueError("thermal.coupling = \"adiabatic\" heats by plastic work: it needs a [plasticity] block")
    if block.source_kind == "manufactured" and (scene.reference.analytic != "manufactured-sine"
                                                or scene.body_force.kind != "manufactured"):
        raise ValueError("thermal.source = \"manufactured\" needs reference.analytic = \"manufactured-sine\" "
                         "and body_force.kind = \"manufactured\"")
    plast = getattr(scene, "plasticity", None)
    opts_ms = []
    ms = block.moving_source
    if ms is not None:
        if block.source != 0:
            raise ValueError("thermal.moving_source and thermal.source: give one heat source")
        axi = scene.elasticity.plane == "axisymmetric"
        if axi and (ms.start[0] != 0 or ms.velocity[0] != 0):
            raise ValueError("thermal.moving_source in an (r, z) model: the source moves along the axis "
                             "(start = [0, z], velocity = [0, v])")
        dim = 3 if axi or len(ms.start) == 3 else 2
        c, v = list(ms.start) + [0.0], list(ms.velocity) + [0.0]
        opts_ms = ["-therm_ms_q", repr(ms.power), "-therm_ms_s", repr(ms.radius), "-therm_ms_dim", str(dim)]
        for k, a, b in zip("xyz", c, v):
            opts_ms += [f"-therm_ms_{k}0", repr(float(a)), f"-therm_ms_v{k}", repr(float(b))]
    if plast is not None and plast.load_time not in (0.0, block.duration):
        raise ValueError(f"plasticity.load_time ({plast.load_time:g} s) and thermal.duration "
                         f"({block.duration:g} s) are two clocks of one process: make them equal")
    files.tables.mkdir(parents=True, exist_ok=True)
    rows = [(LABELS[name], *b.row()) for name, b in block.boundary.items()]
    table = files.tables / "thermal_bc.txt"
    table.write_text(f"{len(rows)}\n" + "".join(f"{lab} {kind} {a!r} {b!r}\n" for lab, kind, a, b in rows))
    opts = ["-therm_k", repr(block.k), "-therm_rho", repr(block.rho), "-therm_c", repr(block.c),
            "-therm_alpha", repr(block.alpha), "-therm_Tref", repr(block.T_ref),
            "-therm_T0", repr(block.T_initial if block.T_initial is not None else block.T_ref),
            "-therm_beta", repr(block.beta), "-therm_coupling", str(COUPLINGS[block.coupling]),
            "-therm_load_time", repr(block.duration), "-therm_bc", str(table),
            "-therm_source_id", str(SOURCES[block.source_kind]),
            "-therm_r", repr(0.0 if block.source == "manufactured" else float(block.source)),
            "-therm_mms_amp", repr(block.mms_amplitude),
            "-therm_tool_T", repr(block.tool_temperature if block.tool_temperature is not None else block.T_ref),
            "-therm_contact_h", repr(block.contact_conductance),
            "-therm_soft", "1" if block.staggered_softening else "0"] + opts_ms
    return opts


def check(block: Thermal, scene) -> None:
    """Rules joining [thermal] with other tables, applied when the scene is read."""
    if block.coupling == "monolithic" and scene.numerics.solver != "direct":
        raise ValueError(f"thermal.coupling = \"monolithic\" solves the non-symmetric (u, T) system: it needs "
                         f"numerics.solver = \"direct\", not {scene.numerics.solver!r} (or thermal.coupling = "
                         f"\"staggered\")")


register(Block(name="thermal", model=Thermal, options=options, fields=("T", "mean_stress"), check=check,
               macro="WITHTHERMAL"))
