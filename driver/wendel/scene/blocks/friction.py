"""The friction, tool, path and force-control keys of the ``[contact]`` block (edp/lib/friction.idp and
edp/lib/tool.idp; contact.py composes them into its table).

>>> Friction(law="tresca", tau_max=1e4).mu
0.0
>>> ToolPath(load_factors=[0.0, 1.0], x=[0.0, 0.1]).rows()[1]
(1.0, 0.1, 0.0, 0.0, 0.0)
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

from pydantic import BaseModel, ConfigDict, Field, model_validator

from . import choice

ROOT = Path(__file__).resolve().parents[4]

FRICTION_LAWS = {"none": 0, "coulomb": 1, "tresca": 2}
"""Friction law name -> ``-fric_law`` id of friction.idp."""
FrictionLawName = choice(FRICTION_LAWS, "friction law")
FRICTION_PASSES = {"compiled": 0, "freefem": 1, "check": 2}
"""How friction.idp does one of its passes over the contact nodes -> its id in ``-fric_frame`` (the Newton
matrix's frame change) and ``-fric_residual`` (the residual pass)."""
FrictionFrameName = choice(FRICTION_PASSES, "friction frame change")
FrictionResidualName = choice(FRICTION_PASSES, "friction residual pass")


class Friction(BaseModel):
    """Friction between the body and the tool (edp/lib/friction.idp, 2D and 3D): Coulomb (optionally capped
    in shear) or Tresca, with stick, slip and inactive sets in the same semismooth Newton as the normal contact."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    law: FrictionLawName = Field("coulomb", description=f"friction law: {', '.join(FRICTION_LAWS)}")
    mu: float = Field(0.0, ge=0, le=10, description="Coulomb friction coefficient [1]")
    tau_max: Optional[float] = Field(None, gt=0, description="Tresca: the slip bound; Coulomb: a cap on the shear traction [Pa]")
    c: float = Field(0.0, ge=0, description="tangential active-set constant [Pa/m]; 0 = the normal one (contact.c)")
    heat_fraction: float = Field(1.0, ge=0, le=1, description="share of the frictional work that heats the body (the rest the tool) [1]")
    frame: FrictionFrameName = Field("compiled", description="the Newton matrix's change to the contact nodes' "
                                     "local frames: compiled (one pass over the matrix, plugin wendel_tool), freefem "
                                     "(the FreeFEM language's sparse products, slower) or check (both; goes on with "
                                     "the compiled one and records friction_frame_diff, their largest relative "
                                     "difference); the same matrix up to round-off")
    residual: FrictionResidualName = Field("compiled", description="the pass over the contact nodes at each "
                                           "residual (the tool's distance, frames, slips, stick/slip sets, rows and "
                                           "current masses): compiled (plugin wendel_tool), freefem (the FreeFEM "
                                           "language's loop, slower) or check (both; goes on with the compiled one "
                                           "and records friction_residual_diff, their largest relative difference); "
                                           "the same numbers")
    trace: bool = Field(False, description="write every contact node's sets (of the last solve and of the current "
                        "state), gap, pressure, traction and slip at every Newton iteration to fem/friction-trace.csv "
                        "(failed increments included: which nodes change their sets while Newton stagnates)")

    @model_validator(mode="after")
    def _law(self):
        if self.law == "tresca" and self.tau_max is None:
            raise ValueError("contact.friction: law = 'tresca' needs tau_max (the slip bound, Pa)")
        if self.law == "coulomb" and self.mu == 0 and self.tau_max is None:
            raise ValueError("contact.friction: law = 'coulomb' needs mu > 0 (or law = 'none')")
        return self


class Tool(BaseModel):
    """A rigid tool at load factor 0: in 2D a counter-clockwise polygon whose corners are rounded by radii
    (a cutting tool: rake face, flank face and the edge radius at their corner); in 3D a closed triangulated
    surface from an STL file (validated by wendel.scene.stl: closed, oriented, finite)."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    vertices: Optional[list[list[float]]] = Field(None, description="2D: polygon vertices [[x, y], ...], counter-clockwise [m]")
    radii: Optional[list[float]] = Field(None, description="corner radius of each vertex, 0 = sharp [m]; default all 0")
    stl: Optional[str] = Field(None, description="3D: a closed surface as an STL file (ASCII or binary, coordinates in m at "
                                                 "load factor 0), relative to the repository root")

    @property
    def stl_path(self) -> Path:
        p = Path(self.stl or "")
        return p if p.is_absolute() else ROOT / p

    @model_validator(mode="after")
    def _shape(self):
        if (self.vertices is None) == (self.stl is None):
            raise ValueError("contact.tool needs either vertices (a 2D polygon) or stl (a 3D surface), not both")
        if self.stl is not None:
            if self.radii is not None:
                raise ValueError("contact.tool.radii belong to a polygon (vertices), not to an STL surface")
            from .. import stl       # numpy: only for scenes with an STL tool (`wendel check` stays light)
            try:
                stl.table(stl.read(self.stl_path), str(self.stl_path))
            except ValueError as e:
                raise ValueError(f"contact.tool.stl: {e}") from None
            return self
        v = self.vertices
        if len(v) < 3 or any(len(p) != 2 for p in v):
            raise ValueError("contact.tool.vertices: at least 3 points [x, y]")
        area = sum(v[k][0] * v[(k + 1) % len(v)][1] - v[(k + 1) % len(v)][0] * v[k][1] for k in range(len(v)))
        if not area > 0:
            raise ValueError("contact.tool.vertices must run counter-clockwise around a non-empty polygon")
        if self.radii is not None and (len(self.radii) != len(v) or any(r < 0 for r in self.radii)):
            raise ValueError("contact.tool.radii: one radius >= 0 per vertex")
        return self


class ToolPath(BaseModel):
    """The tool's rigid motion as piecewise-linear functions of the load factor (extrapolated linearly past
    the ends): translation (x, y, z) and rotation about the axis through contact.center (2D: z); added to
    contact.displacement."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    load_factors: list[float] = Field(..., min_length=1, description="load factors of the path points, increasing [1]")
    x: Optional[list[float]] = Field(None, description="translation along x at those load factors [m]; default 0")
    y: Optional[list[float]] = Field(None, description="translation along y at those load factors [m]; default 0")
    z: Optional[list[float]] = Field(None, description="translation along z at those load factors (3D) [m]; default 0")
    angle: Optional[list[float]] = Field(None, description="rotation about the axis through contact.center, counter-clockwise [deg]; default 0")
    axis: Optional[list[float]] = Field(None, description="the rotation axis [ax, ay, az] (3D; normalised) [1]; default [0, 0, 1] (2D: z only)")

    @model_validator(mode="after")
    def _lengths(self):
        n = len(self.load_factors)
        if any(b <= a for a, b in zip(self.load_factors, self.load_factors[1:])):
            raise ValueError("contact.path.load_factors must increase")
        for key in ("x", "y", "z", "angle"):
            val = getattr(self, key)
            if val is not None and len(val) != n:
                raise ValueError(f"contact.path.{key} needs {n} values (one per load factor)")
        if self.axis is not None and (len(self.axis) != 3 or not math.hypot(*self.axis) > 1e-12):
            raise ValueError("contact.path.axis: three components [ax, ay, az], not all zero")
        return self

    def rows(self) -> list[tuple[float, float, float, float, float]]:
        """(load factor, x, y, z, angle in rad) per path point."""
        n = len(self.load_factors)
        x, y, z, a = (self.x or [0.0] * n), (self.y or [0.0] * n), (self.z or [0.0] * n), (self.angle or [0.0] * n)
        return [(lf, xi, yi, zi, math.radians(ai)) for lf, xi, yi, zi, ai in zip(self.load_factors, x, y, z, a)]


def friction_options(block, files) -> list[str]:
    """The ``-fric_*``/``-tool_*`` options of friction.idp and tool.idp (its macro WITHFRICTION comes from
    wendel.loop.launch.macros); the path and polygon tables are written into the run's tables folder (numbers only)."""
    f = block.friction or Friction(law="none")
    opts = ["-fric_law", str(FRICTION_LAWS[f.law]), "-fric_mu", repr(f.mu),
            "-fric_tau", repr(f.tau_max or 0.0), "-fric_c", repr(f.c), "-fric_heat_fraction", repr(f.heat_fraction),
            "-fric_frame", str(FRICTION_PASSES[f.frame]), "-fric_residual", str(FRICTION_PASSES[f.residual])]
    if f.trace:
        opts += ["-fric_trace", "1"]
    if block.force is not None:
        opts += ["-tool_force", repr(block.force), "-tool_force_tol", repr(block.force_tol)]
    if files is None:
        return opts
    files.tables.mkdir(parents=True, exist_ok=True)
    if block.path is not None:
        rows = block.path.rows()
        p = files.tables / "tool_path.txt"
        p.write_text(f"{len(rows)}\n" + "".join(" ".join(repr(float(v)) for v in r) + "\n" for r in rows))
        opts += ["-tool_path", str(p)]
        if block.path.axis is not None:
            a = block.path.axis
            opts += ["-tool_axis_x", repr(float(a[0])), "-tool_axis_y", repr(float(a[1])), "-tool_axis_z", repr(float(a[2]))]
    if block.tool is not None and block.tool.stl is not None:
        from .. import stl
        opts += ["-tool_stl", str(stl.write_table(block.tool.stl_path, files.tables / "tool_triangles.txt"))]
    elif block.tool is not None:
        v = block.tool.vertices
        radii = block.tool.radii or [0.0] * len(v)
        p = files.tables / "tool_polygon.txt"
        p.write_text(f"{len(v)}\n" + "".join(f"{float(x)!r} {float(y)!r} {float(r)!r}\n" for (x, y), r in zip(v, radii)))
        opts += ["-tool_polygon", str(p)]
    return opts
