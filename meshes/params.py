"""Typed, range-checked parameters of the gmsh builders, and the element count a mesh will have.

A builder declares its keywords by its signature. This module derives a strict model from it: the type
of a keyword comes from :data:`KNOWN` (lengths, intervals, refinement zones) or else from its default
(a float stays a float, a boolean a boolean, a pair of floats a pair of floats); booleans and strings are
never numbers, non-finite values are refused, intervals must increase, ``r_inner < r_outer``.
:func:`estimate_elements` predicts the element count from the domain's size and ``h`` (and a refined
zone), so a scene that would exhaust the machine is refused before gmsh starts.

>>> validate("rectangle", {"h": 0.1, "x": [0, 2]})["x"]
[0.0, 2.0]
>>> validate("rectangle", {"h": 0.1, "x": [2, 0]})
Traceback (most recent call last):
...
ValueError: x: Value error, the interval must increase, got [2.0, 0.0]
>>> round(estimate_elements("rectangle", {"h": 0.1}))
231
"""

from __future__ import annotations

import inspect
import math
import typing
from typing import Annotated, Any, Literal, Optional

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, ValidationError, create_model, model_validator

from .builders import ALGORITHMS_3D, BUILDERS

STRICT = ConfigDict(strict=True, extra="forbid", allow_inf_nan=False)


def _increasing(v: list[float]) -> list[float]:
    if not v[0] < v[1]:
        raise ValueError(f"the interval must increase, got {v}")
    return v


Interval = Annotated[list[float], Field(min_length=2, max_length=2), AfterValidator(_increasing)]
Point = Annotated[list[float], Field(min_length=2, max_length=3)]
Length = Annotated[float, Field(gt=0)]


class Refine(BaseModel):
    """A zone of finer elements: a ball (``center``, ``radius``) or a block (``box = [lo, hi]``), graded
    over ``thickness``; the fine size is ``h`` or ``ratio`` times the scene's h."""

    model_config = STRICT
    h: Optional[Length] = Field(None, description="element size inside the zone [m]")
    ratio: Optional[float] = Field(None, gt=0, le=1, description="fine size as a fraction of geometry.h [1]")
    center: Optional[Point] = Field(None, description="centre of a ball zone [m]")
    radius: Optional[Length] = Field(None, description="radius of a ball zone [m]")
    box: Optional[Annotated[list[Point], Field(min_length=2, max_length=2)]] = Field(
        None, description="corners [lo, hi] of a block zone (a flat block is a layer) [m]")
    thickness: Optional[float] = Field(None, ge=0, description="width of the grading around the zone [m]")

    @model_validator(mode="after")
    def _zone(self):
        if (self.h is None) == (self.ratio is None):
            raise ValueError("give exactly one of refine.h or refine.ratio")
        if self.box is None and (self.center is None or self.radius is None):
            raise ValueError("a refined zone is a ball (center and radius) or a block (box = [lo, hi])")
        if self.box is not None:
            if self.center is not None or self.radius is not None:
                raise ValueError("a refined zone is a ball or a block, not both")
            lo, hi = self.box
            if len(lo) != len(hi) or any(a > b for a, b in zip(lo, hi)):
                raise ValueError(f"refine.box corners must be [lo, hi] with lo <= hi, got {self.box}")
        return self


# Types of keywords by name, for every builder; others are typed by their default.
KNOWN: dict[str, Any] = {
    "x": Interval, "y": Interval, "z": Interval,
    "r": Interval,
    "radius": Length, "r_inner": Length, "r_outer": Length, "length": Length, "height": Length,
    "center": Point,
    "refine": Optional[Refine],
    # orthogonal-cutting
    "depth": Length, "uncut": Length, "pre_cut": Length, "band": Annotated[float, Field(gt=0)],
    "fine": Annotated[float, Field(gt=0, le=1)],
    "algorithm": Literal[tuple(ALGORITHMS_3D)],
    "optimize_threshold": Annotated[float, Field(gt=0, lt=1)],
}


# What a builder keyword means, for `wendel keys` and the README (others: "a keyword of the builder").
HELP = {
    "x": "interval [x0, x1] of the domain along x [m]", "y": "interval [y0, y1] along y [m]",
    "z": "interval [z0, z1] along z [m]", "r": "interval [r0, r1] of the radius [m]",
    "radius": "radius of the body [m]", "r_inner": "inner radius, below r_outer [m]",
    "r_outer": "outer radius [m]", "length": "length of the body [m]", "height": "height of the body [m]",
    "center": "centre of the body [m]", "structured": "transfinite (structured) mesh, for convergence studies",
    "quarter": "model a quarter with symmetry planes", "refine": "a zone of finer elements (table below)",
    "depth": "depth of the workpiece below the machined level [m]",
    "uncut": "uncut chip thickness: the layer to be cut on top [m]",
    "pre_cut": "length of the machined step the tool starts against [m]",
    "band": "depth of the refined band below the machined level, in uncut thicknesses [1]",
    "fine": "element size in the refined band as a fraction of h [1]",
    "algorithm": "3D: gmsh's tetrahedral algorithm, delaunay (gmsh's default) or hxt (3-10x faster meshing "
                 "without Netgen's optimization: `wendel bench gmsh3d`, `step42-accuracy`; another mesh)",
    "optimize": "3D: gmsh's Netgen optimization of the tetrahedra (false: meshing about 6x faster, the worst "
                "element about half as good; another mesh, so other results at the discretization level)",
    "optimize_threshold": "3D: gmsh's own optimizer (in every 3D mesh) reworks the tetrahedra of quality (gamma) "
                          "below it: 0.3 is gmsh's default; 0.6 without Netgen meshes hertz-force-3d 2-4x faster "
                          "than Netgen (`wendel bench gmsh3d`; another mesh)",
}


def keyword_rows() -> list[tuple[str, str, str, str]]:
    """(key, type, defaults, meaning) of every builder keyword, one row per name, for the key table."""
    by_name: dict[str, list[tuple[str, Any]]] = {}
    for builder in sorted(BUILDERS):
        for name, f in model(builder).model_fields.items():
            if name != "h":
                by_name.setdefault(name, []).append((builder, f))
    rows = []
    for name, items in sorted(by_name.items()):
        f = items[0][1]
        ann = typing.get_args(f.annotation)[0] if typing.get_origin(f.annotation) is Annotated else f.annotation
        typ = ("table, optional" if name == "refine" else "str, one of " + ", ".join(typing.get_args(ann))
               if typing.get_origin(ann) is Literal else str(ann) if "[" in str(ann) else ann.__name__)
        defaults = "; ".join(f"{b}: {'required' if g.is_required() else repr(g.default)}" for b, g in items)
        rows.append((f"geometry.{name}", typ, defaults,
                     f"{HELP.get(name, 'a keyword of the builder')} (builders: {', '.join(b for b, _ in items)})"))
    kinds = {"center": "list[float]", "box": "list[list[float]]"}
    for name, f in Refine.model_fields.items():
        rows.append((f"geometry.refine.{name}", f"{kinds.get(name, 'float')}, optional", "None", f.description or ""))
    return rows


def _type_of(name: str, default: Any):
    if name in KNOWN:
        return KNOWN[name]
    if isinstance(default, bool):
        return bool
    if isinstance(default, int):
        return int
    if isinstance(default, float):
        return float
    if isinstance(default, (tuple, list)) and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                  for v in default):
        return Annotated[list[float], Field(min_length=len(default), max_length=len(default))]
    if isinstance(default, str):
        return str
    return Any


_MODELS: dict[str, type[BaseModel]] = {}


def model(builder: str) -> type[BaseModel]:
    """The strict parameter model of ``builder`` (derived from its signature, cached)."""
    if builder not in _MODELS:
        fields = {}
        for name, p in inspect.signature(BUILDERS[builder]).parameters.items():
            if name == "path":
                continue
            default = p.default if p.default is not inspect.Parameter.empty else ...
            default = list(default) if isinstance(default, tuple) else default
            typ = Length if name == "h" else _type_of(name, None if default is ... else default)
            fields[name] = (typ, default)
        _MODELS[builder] = create_model(f"{builder.title().replace('-', '')}Parameters", __config__=STRICT,
                                        **fields)
    return _MODELS[builder]


def validate(builder: str, params: dict) -> dict:
    """``params`` checked and normalized for ``builder``; ValueError names the key (dotted) otherwise."""
    try:
        values = model(builder).model_validate(params)
    except ValidationError as exc:
        err = exc.errors()[0]
        key = ".".join(str(p) for p in err["loc"] if not str(p).startswith("function-after"))
        msg = "unknown key for builder " + repr(builder) if err["type"] == "extra_forbidden" else err["msg"]
        raise ValueError(f"{key}: {msg}") from None
    out = values.model_dump(exclude_none=True)
    if out.get("r_inner") is not None and out.get("r_outer") is not None and not out["r_inner"] < out["r_outer"]:
        raise ValueError(f"r_inner: must be smaller than r_outer ({out['r_inner']} >= {out['r_outer']})")
    if out.get("refine") is None:
        out.pop("refine", None)
    return {k: v for k, v in out.items() if k in params or k == "h"}


# Elements per unit measure at size h: equilateral triangles (sqrt(3)/4 h^2), gmsh's tetrahedra
# (about 8.5 per h^3 measured on the box builder: a regular tetrahedron fills h^3 / (6 sqrt 2)).
_PER = {2: 4 / math.sqrt(3), 3: 6 * math.sqrt(2)}


def _domain(builder: str, p: dict) -> tuple[list[float], list[float], float] | None:
    """Bounding box (lo, hi) and area or volume of the builder's domain, where its parameters tell it."""
    signature = inspect.signature(BUILDERS[builder]).parameters
    full = {k: v.default for k, v in signature.items() if v.default is not inspect.Parameter.empty}
    full.update(p)
    if builder == "ring":
        r0, r1, quarter = full["r_inner"], full["r_outer"], full.get("quarter")
        return [0.0 if quarter else -r1] * 2, [r1, r1], math.pi * (r1 ** 2 - r0 ** 2) / (4 if quarter else 1)
    if builder == "disk":
        c, r = full["center"], full["radius"]
        return [c[0] - r, c[1] - r], [c[0] + r, c[1] + r], math.pi * r ** 2
    if builder == "sphere_section":          # (r, z) sections: the area of the section
        r0, r1, half = full["r_inner"], full["r_outer"], full.get("half")
        return [0.0, -r1 if half else 0.0], [r1, r1], math.pi * (r1 ** 2 - r0 ** 2) / (2 if half else 4)
    if builder == "hollow_cylinder_section":
        r0, r1, z = full["r_inner"], full["r_outer"], full["z"]
        return [r0, z[0]], [r1, z[1]], (r1 - r0) * (z[1] - z[0])
    if builder == "notched_bar":
        r, half = full["radius"], full["length"] / 2
        return [0.0, 0.0], [r, half], r * half
    if "r" in full and "z" in full:
        return [full["r"][0], full["z"][0]], [full["r"][1], full["z"][1]], \
            (full["r"][1] - full["r"][0]) * (full["z"][1] - full["z"][0])
    if "x" in full and "y" in full:
        axes = [full["x"], full["y"]] + ([full["z"]] if "z" in full else [])
        return [a[0] for a in axes], [a[1] for a in axes], math.prod(a[1] - a[0] for a in axes)
    return None


def estimate_elements(builder: str, params: dict) -> float | None:
    """Estimated element count of the mesh ``builder`` makes with ``params`` (None: not estimable).

    A guard, not a prediction: uniform meshes of a few hundred elements or more come out within 15 % of
    gmsh's count on the scenes of workflows/; a refined zone (clipped to the domain, its grading counted
    as a sixth of its width) is overestimated by up to 5x (hertz-3d: 89k estimated, 19.7k made).
    """
    box = _domain(builder, params)
    if box is None:
        return None
    lo, hi, measure = box
    dim, h = len(lo), params["h"]
    if h ** dim == 0 or (params.get("refine") and (params["refine"].get("h") or params["refine"]["ratio"] * h) ** dim == 0):
        return math.inf                # h so small that h^dim underflows: no machine meshes it
    count = _PER[dim] * measure / h ** dim
    refine = params.get("refine")
    if refine:
        h_in = refine.get("h") or refine["ratio"] * h
        pad = (refine.get("thickness") or 0.0) / 6
        if refine.get("box"):
            zlo = [a - pad for a in refine["box"][0][:dim]]
            zhi = [b + pad for b in refine["box"][1][:dim]]
            shape = 1.0
        else:
            c, r = list(refine["center"]) + [0.0], refine["radius"] + pad
            zlo, zhi = [c[i] - r for i in range(dim)], [c[i] + r for i in range(dim)]
            shape = math.pi / 4 if dim == 2 else math.pi / 6
        sides = [max(min(b, d1) - max(a, d0), h_in) for a, b, d0, d1 in zip(zlo, zhi, lo, hi)]
        count += _PER[dim] * min(shape * math.prod(sides), measure) / h_in ** dim
    return count
