"""The ``[contact]`` block: frictionless Signorini contact with one rigid obstacle (edp/lib/contact.idp).

The contact boundary is a named boundary whose outward normal is along a coordinate axis (``normal``,
e.g. ``"+y"``); the gap is measured along that axis in the undeformed configuration. Obstacle shapes go
through a registry of names to the integer ids of ``-contact_obstacle``:

>>> sorted(OBSTACLES.items(), key=lambda kv: kv[1])
[('plane', 1), ('ball', 2), ('cylinder', 3), ('heightmap', 4), ('tool', 5)]
>>> Contact(boundary="top", obstacle="ball", center=[0.0, 1.0], radius=1.0).normal
'+y'
>>> options(Contact(boundary="top", normal="+z", displacement=-1e-3), None, None)[:6]
['-contact_label', '4', '-contact_axis', '2', '-contact_dir', '1']

Friction, a tool of any shape (2D polygon), a tool path or force control switch to edp/lib/friction.idp
(current configuration, 2D and 3D) through the extra macro ``-DWITHFRICTION=1`` (wendel.loop.launch.macros):

>>> c = Contact(boundary="bottom", normal="-y", friction={"law": "coulomb", "mu": 0.3})
>>> c.current_configuration, options(c, None, None)[-14:-10]
(True, ['-fric_law', '1', '-fric_mu', '0.3'])

The scalar membrane obstacle problem (deal.II step-41, ``edp/obstacle.edp``) is the problem
``membrane-obstacle`` with its table ``[obstacle]``:

>>> MembraneObstacle(shape="radial").c
100.0
"""

from __future__ import annotations

from pathlib import Path
from typing import Optional

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

import json
import shutil

from . import Block, Problem, choice, register, register_problem
from ...meshes import LABELS
from .friction import FRICTION_LAWS, Friction, Tool, ToolPath, friction_options  # noqa: F401 (re-exported)

OBSTACLES = {"plane": 1, "ball": 2, "cylinder": 3, "heightmap": 4, "tool": 5}
"""Obstacle name -> ``-contact_obstacle`` id of contact.idp."""
REFERENCES = {"hertz": 1}
"""Reference name -> ``-contact_ref`` id of contact.idp."""
AXES = {"x": 0, "y": 1, "z": 2}

BoundaryName = choice(LABELS, "boundary")
ObstacleName = choice(OBSTACLES, "obstacle")
ContactReferenceName = choice(REFERENCES, "contact reference")
ROOT = Path(__file__).resolve().parents[4]


class Contact(BaseModel):
    """A rigid obstacle pressed on a named boundary; PDAS (semismooth Newton) in the Newton loop."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    boundary: BoundaryName = Field(..., description="named contact boundary (meshes/labels.py)")
    normal: str = Field("+y", description="outward normal of that boundary: +x, -x, +y, -y, +z or -z")
    obstacle: ObstacleName = Field("plane", description=f"obstacle shape: {', '.join(OBSTACLES)}")
    center: list[float] = Field([0.0, 0.0, 0.0], description="plane point, ball/cylinder centre, heightmap base and centre [m]")
    radius: float = Field(1.0, gt=0, description="ball or cylinder radius [m]")
    cylinder_axis: str = Field("x", description="3D cylinder axis direction: x, y or z (not the normal's)")
    displacement: float = Field(0.0, description="obstacle displacement along the normal axis at load factor 1 [m] (signed along the axis)")
    image: Optional[str] = Field(None, description="heightmap: PGM/PPM image, relative to the repository root; bright = closer to the body")
    height: float = Field(0.0, ge=0, description="heightmap: protrusion of white over black towards the body [m]")
    size: list[float] = Field([1.0, 1.0], description="heightmap: footprint along the two tangential axes [m]")
    c: float = Field(0.0, ge=0, description="active-set constant [Pa/m]; 0 = E / h_min (the solution does not depend on it)")
    reference: Optional[ContactReferenceName] = Field(None, description=f"reference solution: {', '.join(REFERENCES)} (contact size and peak pressure)")
    friction: Optional[Friction] = Field(None, description="friction law (absent: frictionless)")
    tool: Optional[Tool] = Field(None, description="obstacle = 'tool': the polygon with rounded corners (2D)")
    path: Optional[ToolPath] = Field(None, description="the obstacle's motion along the load factor (3D: translation only)")
    force: Optional[float] = Field(None, gt=0, description="force control: the pressing force along the normal axis at load "
                                   "factor 1 [N; N/m in 2D]; the tool's position along that axis is solved for (displacement = first guess)")
    force_tol: float = Field(1e-9, gt=0, lt=1e-2, description="force control: relative tolerance on the force [1]")


    @field_validator("normal")
    @classmethod
    def _normal(cls, v):
        if len(v) != 2 or v[0] not in "+-" or v[1] not in AXES:
            raise ValueError(f"normal must be one of +x, -x, +y, -y, +z, -z; got {v!r}")
        return v



    @model_validator(mode="after")
    def _consistency(self):
        if self.obstacle == "heightmap":
            if self.image is None:
                raise ValueError("contact.obstacle = 'heightmap' needs contact.image")
            if not self.image_path.is_file():
                raise ValueError(f"contact.image: no such file {self.image_path}")
            image_size(self.image_path)
        if self.cylinder_axis not in AXES or (self.obstacle == "cylinder" and self.cylinder_axis == self.normal[1]):
            raise ValueError("contact.cylinder_axis must be x, y or z and differ from the normal's axis")
        if len(self.center) not in (2, 3) or len(self.size) != 2:
            raise ValueError("contact.center has 2 or 3 components, contact.size 2")
        if self.reference == "hertz" and self.obstacle not in ("ball", "tool"):
            raise ValueError("contact.reference = 'hertz' needs obstacle = 'ball' or 'tool' (edge radius = contact.radius)")
        if (self.obstacle == "tool") != (self.tool is not None):
            raise ValueError("contact.obstacle = 'tool' and the table contact.tool go together")
        if self.current_configuration and self.obstacle in ("cylinder", "heightmap"):
            raise ValueError(f"contact.friction, contact.tool and contact.path work with obstacle = plane, ball or tool, "
                             f"not {self.obstacle!r}")
        return self

    @property
    def current_configuration(self) -> bool:
        """Friction, a tool or a path: edp/lib/friction.idp (gap and normal in the current configuration)."""
        return self.friction is not None or self.tool is not None or self.path is not None or self.force is not None

    @property
    def image_path(self) -> Path:
        p = Path(self.image or "")
        return p if p.is_absolute() else ROOT / p


MAX_PIXELS = 16_000_000     # a height map larger than 4000 x 4000 is refused (FreeFEM reads it as text)


def image_size(path: Path) -> tuple[int, int]:
    """(width, height) of the PGM/PPM image ``path``; ValueError naming contact.image if it is not one of
    those formats or its size is absurd.

    >>> image_size(ROOT / "workflows" / "images" / "stamp.pgm")[0] > 1
    True
    """
    head = path.read_bytes()[:4096]
    if head[:2] not in (b"P2", b"P3", b"P5", b"P6"):
        raise ValueError(f"contact.image: {path} is not a PGM or PPM image (no P2/P3/P5/P6 header); convert it, "
                         f"e.g. with `convert IMAGE -compress none OUT.pgm`")
    words = []
    for line in head[2:].split(b"\n"):
        words += line.split(b"#", 1)[0].split()
        if len(words) >= 2:
            break
    try:
        w, h = int(words[0]), int(words[1])
    except (IndexError, ValueError):
        raise ValueError(f"contact.image: {path}: unreadable PGM/PPM header") from None
    if not (2 <= w <= 8192 and 2 <= h <= 8192 and w * h <= MAX_PIXELS):
        raise ValueError(f"contact.image: {path} is {w} x {h} pixels; wendel takes 2 to 8192 per side and at "
                         f"most {MAX_PIXELS:,} pixels")
    return w, h


def in_current_configuration(block: Contact, scene) -> bool:
    """Gap and normal in the current configuration (edp/lib/friction.idp, ``-DWITHFRICTION=1``): friction, a tool,
    a path or force control; and any plane or ball obstacle of a plane or 3D updated-Lagrangian scene (without
    friction: law none), whose body moves far from the launch mesh between remeshes (friction.idp has no
    (r, z) weights: axisymmetric scenes keep contact.idp)."""
    ul = scene is not None and scene.kinematics.updated_lagrangian and block.obstacle in ("plane", "ball", "tool") \
        and scene.elasticity.plane != "axisymmetric"
    return block.current_configuration or ul


def options(block: Contact, scene, files) -> list[str]:
    """``-contact_*`` options of contact.idp (numbers, ids and the image path only)."""
    c = list(block.center) + [0.0] * (3 - len(block.center))
    opts = ["-contact_label", str(LABELS[block.boundary]), "-contact_axis", str(AXES[block.normal[1]]),
            "-contact_dir", "1" if block.normal[0] == "+" else "-1",
            "-contact_obstacle", str(OBSTACLES[block.obstacle]),
            "-contact_cx", repr(c[0]), "-contact_cy", repr(c[1]), "-contact_cz", repr(c[2]),
            "-contact_R", repr(block.radius), "-contact_cyl_axis", str(AXES[block.cylinder_axis]),
            "-contact_disp", repr(block.displacement), "-contact_amp", repr(block.height),
            "-contact_lx", repr(block.size[0]), "-contact_ly", repr(block.size[1]), "-contact_c", repr(block.c),
            "-contact_ref", str(REFERENCES.get(block.reference, 0))]
    if block.obstacle == "heightmap":
        opts += ["-contact_image", str(block.image_path)]
    if in_current_configuration(block, scene):
        opts += friction_options(block, files)
    return opts


def _check(block: Contact, scene) -> None:
    """Scene-level rules of friction.idp: a non-symmetric Newton matrix (no CG)."""
    if block.current_configuration and scene.numerics.solver == "cg":
        raise ValueError("contact.friction/tool/path/force give a non-symmetric Newton matrix: "
                         "numerics.solver must be 'direct' or 'ffddm', not 'cg'")


register(Block(name="contact", model=Contact, options=options, check=_check, macro="WITHCONTACT",
               fields=("contact_pressure", "contact_active", "contact_gap", "friction_traction", "friction_slip",
                       "friction_state")))


MEMBRANE_SHAPES = {"staircase": 1, "radial": 2}
MembraneShapeName = choice(MEMBRANE_SHAPES, "membrane obstacle")
"""Membrane obstacle name -> ``-obst_id`` of obstacle.edp."""


class MembraneObstacle(BaseModel):
    """The membrane obstacle problem -Laplace(u) = f, u >= g, by PDAS (edp/obstacle.edp)."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    shape: MembraneShapeName = Field("staircase", description="obstacle and data: staircase (step-41, u = 0 on the boundary), "
                       "radial (g = sqrt(1 - r^2), exact solution as boundary data and reference)")
    f: Optional[float] = Field(None, description="load density [1/m]; default -10 (staircase), 0 (radial)")
    c: float = Field(100.0, gt=0, description="active-set constant [1/m^2]; the solution does not depend on it")



def _membrane_entry(scene, dimension: int) -> str:
    if dimension != 2:
        raise ValueError("problem 'membrane-obstacle' is 2D")
    return "obstacle.edp"


def _membrane_options(scene, files, dimension: int) -> list[str]:
    o = scene.obstacle or MembraneObstacle()
    opts = ["-obst_id", str(MEMBRANE_SHAPES[o.shape]), "-obst_c", repr(o.c)]
    if o.f is not None:
        opts += ["-obst_f", repr(o.f)]
    return opts


register(Block(name="obstacle", model=MembraneObstacle, options=lambda *_: [], fields=("u", "lambda", "active", "gap"),
               mechanics=False))
register_problem(Problem(name="membrane-obstacle", entry=_membrane_entry, options=_membrane_options,
                         tables=("obstacle",)))


def bench_obstacle(quick: bool, workdir) -> list[dict]:
    """step-41 at 3 mesh sizes: active-set iterations, DoFs, wall time (register as ``wendel bench obstacle``)."""
    from ...loop import run
    from .. import load

    scene = ROOT / "workflows" / "obstacle.toml"
    h0 = load(scene).geometry.h
    rows = []
    for n in ((16, 32, 64) if quick else (32, 64, 128)):
        out = workdir / f"n{n}"
        shutil.rmtree(out, ignore_errors=True)
        root = run(scene, out=out, scale=2.0 / n / h0, png=False, progress=lambda *_: None)
        s = json.loads((root / "summary.json").read_text())
        last = s["last_increment"]
        rows.append({"cells_per_side": n, "dofs": s["dofs"], "active_set_iterations": last["active_set_iterations"],
                     "step41_iterations": 18 if n == 128 else None, "active_nodes": last["active_nodes"],
                     "wall_time": s["wall_time"], "solve_time": last["time_solve"]})
    return rows
