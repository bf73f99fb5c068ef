"""The ``[drilling]`` block: the drilling process at workpiece scale (driver: :mod:`wendel.drilling`).

The drill (diameter ``D``, point angle ``sigma``, feed ``f`` per revolution, spindle speed ``n``) advances
from ``start_depth`` to ``depth`` (tip depths below the entry face) in ``steps`` removal steps, may dwell
at the bottom, and is withdrawn; the part then cools. The block adds no FreeFEM module of its own: the
driver cuts the bore from the workpiece at every step (meshes/drilling.py), transfers the state and puts
the process loads on the new bore surfaces through the thermal and traction tables of the mechanics.

Cutting force by Kienzle's law per cutting edge (Toenshoff & Denkena, *Basics of Cutting and Abrasive
Processes*, Springer 2013, ch. 2 and 8 (drilling); Kienzle & Victor 1957): with ``kappa = sigma / 2``,
chip thickness ``h = f/2 sin(kappa)``, chip width ``b = D / (2 sin(kappa))`` (main cutting edges; the chisel
edge is not modelled),

    F_c = b k_c1.1 (h / 1 mm)^(-m_c) h,   torque M = 2 F_c D / 4,   P_c = 2 pi n M,

and the same law with ``k_f1.1, m_f`` for the axial (feed) force per edge, thrust ``F_z = 2 F_f``.

>>> d = Drilling(diameter=0.01, feed=0.2e-3, speed=1000.0, depth=0.01, kc11=1160e6, mc=0.26)
>>> round(d.drill_torque(), 4), round(d.power(), 1)        # grey cast iron, D = 10 mm, f = 0.2 mm, 1000 1/min
(5.4929, 575.2)
"""

from __future__ import annotations

import math
from typing import Literal, Optional

from pydantic import BaseModel, ConfigDict, Field, model_validator

from . import Block, register

H0 = 1e-3    # m: Kienzle's reference chip thickness (1 mm)
DRILLED_BUILDERS = ("drilled-cylinder", "drilled-block", "drilled-section")
FORCE_MODELS = ("kienzle", "given")


class Probe(BaseModel):
    """A thermocouple: its name and position."""

    model_config = ConfigDict(extra="forbid")

    name: str = Field(..., min_length=1, description="name of the thermocouple (column of tables/probes.csv)")
    position: list[float] = Field(..., min_length=3, max_length=3, description="position (x, y, z) [m]")


class Drilling(BaseModel):
    """Drill, process and outputs of a drilling scene."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    diameter: float = Field(..., gt=0, description="drill diameter D [m]")
    point_angle: float = Field(118.0, gt=30, lt=180, description="point angle sigma of the drill [deg]")
    feed: float = Field(..., gt=0, description="feed per revolution f [m]")
    speed: float = Field(..., gt=0, description="spindle speed n [1/min]")
    depth: float = Field(..., gt=0, description="final depth of the drill tip below the entry face [m]")
    start_depth: float = Field(0.0, ge=0, description="tip depth at the start (a pre-drilled bore) [m]")
    steps: int = Field(5, ge=1, description="removal steps from start_depth to depth [1]")
    dwell: float = Field(0.0, ge=0, description="time the drill turns at the bottom without advancing [s]")
    dwell_steps: int = Field(1, ge=1, description="steps of the dwell (each one remeshes and transfers) [1]")
    cooling: float = Field(0.0, ge=0, description="cooling time after the drill is withdrawn [s]")
    cooling_steps: int = Field(5, ge=1, description="increments of the cooling phase [1]")
    force: Literal["kienzle", "given"] = Field("kienzle", description="force model: kienzle (k_c1.1, m_c) or given (torque, thrust)")
    kc11: float = Field(0.0, ge=0, description="Kienzle specific cutting force k_c1.1 at h = 1 mm, b = 1 mm [Pa = N/m^2]")
    mc: float = Field(0.25, ge=0, lt=1, description="Kienzle exponent m_c [1]")
    kf11: float = Field(0.0, ge=0, description="Kienzle specific feed force k_f1.1 (0: thrust below) [Pa]")
    mf: float = Field(0.5, ge=0, lt=1, description="Kienzle exponent m_f [1]")
    torque: float = Field(0.0, ge=0, description="drilling torque M with force = given [N m]")
    thrust: float = Field(0.0, ge=0, description="thrust (axial force) with force = given, or with kienzle when kf11 = 0 [N]")
    eta_w: float = Field(0.1, ge=0, le=1, description="fraction of the cutting power that flows into the workpiece [1]")
    wall_fraction: float = Field(0.3, ge=0, le=1, description="share of the workpiece heat entering along the bore wall (rest at the bottom) [1]")
    bore_h: float = Field(0.0, ge=0, description="convection coefficient on the bore surfaces (MQL, air; 0: none) [W/m^2/K]")
    bore_T_inf: float = Field(293.15, gt=0, description="ambient temperature of the bore convection [K]")
    transfer: Literal["conservative", "interpolate"] = Field("conservative", description="temperature onto the new mesh: conservative (lumped L2 projection, keeps the heat) or interpolate (nodal interpolation of remesh_state)")
    h_bore: Optional[float] = Field(None, gt=0, description="element size at the bore wall and bottom [m]; default geometry.h / 3")
    grade: Optional[float] = Field(None, gt=0, description="distance over which the size grows from h_bore to geometry.h [m]; default 2 D")
    probes: list[Probe] = Field(default_factory=list, description="thermocouples ([[drilling.probes]] tables: name, position)")
    bore_bins: int = Field(10, ge=2, description="depth bins of the bore diameter error profile [1]")

    @model_validator(mode="after")
    def _process(self):
        if self.depth <= self.start_depth and self.dwell == 0:
            raise ValueError("depth must exceed start_depth (or give a dwell: a drill that does not advance)")
        if self.force == "kienzle" and self.kc11 == 0:
            raise ValueError("force = \"kienzle\" needs kc11 (the material's k_c1.1 [Pa])")
        names = [p.name for p in self.probes]
        if len(set(names)) != len(names):
            raise ValueError(f"probes: two thermocouples have the same name ({', '.join(names)})")
        return self

    # ---- process model (formulas in the module docstring)
    @property
    def kappa(self) -> float:
        """Half the point angle (rad)."""
        return math.radians(self.point_angle) / 2

    def _kienzle(self, k11: float, m: float) -> float:
        """Force per cutting edge (N) of specific force ``k11`` (Pa at 1 mm) and exponent ``m``."""
        h = self.feed / 2 * math.sin(self.kappa)
        b = self.diameter / (2 * math.sin(self.kappa))
        return b * h * k11 * (h / H0) ** (-m)

    def drill_torque(self) -> float:
        """Drilling torque (N m): 2 edges x F_c x D/4 (kienzle), or the given torque."""
        if self.force == "given":
            return self.torque
        return 2 * self._kienzle(self.kc11, self.mc) * self.diameter / 4

    def power(self) -> float:
        """Cutting power P_c = 2 pi n M (W)."""
        return 2 * math.pi * self.speed / 60 * self.drill_torque()

    def thrust_force(self) -> float:
        """Axial force on the workpiece (N): 2 edges x Kienzle feed force, or the given thrust."""
        if self.force == "kienzle" and self.kf11 > 0:
            return 2 * self._kienzle(self.kf11, self.mf)
        return self.thrust

    def advance_time(self) -> float:
        """Time to drill from start_depth to depth (s): (depth - start_depth) / (f n)."""
        return max(0.0, self.depth - self.start_depth) / (self.feed * self.speed / 60)

    def total_time(self) -> float:
        return self.advance_time() + self.dwell + self.cooling


def check(block: Drilling, scene) -> None:
    """A drilling scene needs a drilled-* builder, a thermal block with time, and a clamped base."""
    g = scene.geometry
    if g.builder not in DRILLED_BUILDERS:
        raise ValueError(f"[drilling] needs geometry.builder one of {', '.join(DRILLED_BUILDERS)}, not {g.builder!r}")
    if (g.builder == "drilled-section") != (scene.elasticity.plane == "axisymmetric"):
        raise ValueError("geometry.builder: the (r, z) section drilled-section goes with elasticity.plane = "
                         "'axisymmetric', and an axisymmetric drilling scene needs drilled-section")
    given = sorted(set(g.model_extra or {}) & {"depth", "diameter", "point_angle", "h_bore", "grade"})
    if given:
        raise ValueError(f"geometry.{given[0]}: the drill and its bore come from [drilling], not [geometry]")
    th = getattr(scene, "thermal", None)
    if th is None:
        raise ValueError("[drilling] heats the workpiece: it needs a [thermal] block")
    if th.duration not in (0.0, block.total_time()):
        raise ValueError(f"thermal.duration: the process time of a drilling scene is set by [drilling] "
                         f"({block.total_time():g} s); leave it out")
    if getattr(scene, "plasticity", None) is not None and scene.plasticity.load_time not in (0.0, block.total_time()):
        raise ValueError("plasticity.load_time: the process time of a drilling scene is set by [drilling]; leave it out")
    for name in ("bore_wall", "bore_bottom"):
        if name in th.boundary or name in scene.boundary:
            raise ValueError(f"thermal.boundary.{name}: the bore's loads come from [drilling]")


register(Block(name="drilling", model=Drilling, options=lambda block, scene, files: [], check=check))
