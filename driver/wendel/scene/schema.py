"""The scene schema: every key once, with type, default, unit, range and help.

Validation, ``wendel check``, the CLI help and the README's key table all come from these models.
Lengths in m, stresses and moduli in Pa, forces per volume in N/m^3, times in s. One file (about 320
lines) on purpose: the single source of truth of the keys; the optional blocks' tables are in
:mod:`wendel.scene.blocks`.

>>> Material(E=2.5, nu=0.25).nu
0.25
"""

from __future__ import annotations

import inspect
import typing
from typing import Literal, Optional

from pydantic import BaseModel, ConfigDict, Field, create_model, field_validator, model_validator

from .blocks import BLOCKS, PROBLEMS, choice, load_all
from ..results.comparisons import COMPARISONS
from ..meshes import BUILDERS
from .petsc import PRECONDITIONERS, PcName, check_options
from .kernels import ASSEMBLIES, check as check_kernels
from .axisymmetric import REFERENCES as AXI_REFERENCES, check as check_axisymmetric

# Names a scene may use, mapped to the integer ids of edp/lib/loads.idp (never code).
BODY_FORCES = {"none": 0, "constant": 1, "step8-discs": 2, "manufactured": 3}
ANALYTIC_REFERENCES = {"manufactured-sine": 1}
SOLVERS = ("direct", "cg", "ffddm", "petsc")
KINEMATICS = ("small-strain", "updated-lagrangian")

BodyForceName = choice(BODY_FORCES, "body force")
SolverName = choice(SOLVERS, "solver")
AnalyticName = choice(ANALYTIC_REFERENCES, "analytic reference")
ComparisonName = choice(COMPARISONS, "comparison")
KinematicsName = choice(KINEMATICS, "kinematics")
AssemblyName = choice(ASSEMBLIES, "assembly")
AxiReferenceName = choice(AXI_REFERENCES, "axisymmetric reference")


class Strict(BaseModel):
    """Base of every scene table: unknown keys are errors."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)


class Geometry(Strict):
    """Where the mesh comes from: a builder of meshes/ with its parameters, or a mesh file."""

    model_config = ConfigDict(extra="allow")
    builder: Optional[str] = Field(None, description="gmsh builder of meshes/ (rectangle, box, ring, ...)")
    mesh: Optional[str] = Field(None, description="MSH 2.2 file, relative to the scene file")
    h: float = Field(0.1, gt=0, description="target element size [m]")
    dimension: Optional[int] = Field(None, description="2 or 3; needed only with `mesh`")

    @model_validator(mode="after")
    def _source(self):
        if (self.builder is None) == (self.mesh is None):
            raise ValueError("give exactly one of `builder` or `mesh`")
        if self.builder is not None:
            if self.builder not in BUILDERS:
                raise ValueError(f"unknown builder {self.builder!r}; valid: {', '.join(sorted(BUILDERS))}")
            allowed = set(inspect.signature(BUILDERS[self.builder]).parameters) - {"path", "h"}
            unknown = set(self.model_extra or {}) - allowed
            if unknown:
                raise ValueError(
                    f"unknown key(s) {', '.join(sorted(unknown))} for builder {self.builder!r}; "
                    f"valid: h, {', '.join(sorted(allowed))}")
        elif self.model_extra:
            raise ValueError(f"unknown key(s) {', '.join(sorted(self.model_extra))} next to `mesh`")
        elif self.dimension not in (2, 3):
            raise ValueError("a `mesh` file needs `dimension = 2` or `3`")
        return self

    @property
    def params(self) -> dict:
        """Builder parameters (everything but builder/mesh/dimension)."""
        return {"h": self.h, **(self.model_extra or {})}


class Material(Strict):
    """Isotropic elastic constants."""

    E: float = Field(..., gt=0, description="Young's modulus [Pa]")
    nu: float = Field(..., gt=-1, lt=0.5, description="Poisson's ratio [1], in (-1, 0.5)")


class Elasticity(Strict):
    """Options of the elastic part (present in every mechanical scene)."""

    plane: Literal["strain", "stress", "axisymmetric"] = Field(
        "strain", description="2D hypothesis; axisymmetric: x = r >= 0, y = z, hoop strain and 2 pi r weights")
    order: int = Field(1, ge=1, le=2, description="Lagrange order of the displacement; 2: 2D elastic scenes "
                       "without remeshing (-DPk=P2)")
    reference: Optional[AxiReferenceName] = Field(
        None, description=f"closed form of an axisymmetric scene: {', '.join(AXI_REFERENCES)}")


class Boundary(Strict):
    """Conditions on one named boundary; each displacement component is optional (free if absent)."""

    ux: Optional[float] = Field(None, description="prescribed x displacement at load factor 1 [m]")
    uy: Optional[float] = Field(None, description="prescribed y displacement at load factor 1 [m]")
    uz: Optional[float] = Field(None, description="prescribed z displacement at load factor 1 [m]")
    traction: Optional[list[float]] = Field(None, description="traction vector at load factor 1 [Pa]")
    pressure: Optional[float] = Field(None, description="normal pressure at load factor 1 [Pa]")
    rotation: Optional[float] = Field(None, description="prescribed motion: rigid rotation in the x-y plane "
                                      "about `center` (3D: about the z axis, u_z = 0) at load factor 1 (the "
                                      "angle grows linearly with it) [rad]")
    gradient: Optional[list[float]] = Field(None, description="prescribed motion: in-plane displacement "
                                            "gradient [gxx, gxy, gyx, gyy] about `center` at load factor 1 [1]")
    center: list[float] = Field([0.0, 0.0], description="centre of the prescribed motion [m]")

    @field_validator("traction")
    @classmethod
    def _traction(cls, v):
        if v is not None and len(v) not in (2, 3):
            raise ValueError("traction has 2 (2D) or 3 (3D) components")
        return v

    @model_validator(mode="after")
    def _motion(self):
        if self.rotation is not None or self.gradient is not None:
            if self.gradient is not None and len(self.gradient) != 4:
                raise ValueError("gradient has 4 components [gxx, gxy, gyx, gyy]")
            if len(self.center) != 2:
                raise ValueError("center has 2 components [x, y]")
            if any(v is not None for v in (self.ux, self.uy, self.uz)):
                raise ValueError("rotation/gradient prescribe both components: no ux/uy/uz beside them")
        return self

    @property
    def motion(self) -> bool:
        """Whether the boundary follows a prescribed rotation/affine motion."""
        return self.rotation is not None or self.gradient is not None


class BodyForce(Strict):
    """A named body force (edp/lib/loads.idp)."""

    kind: BodyForceName = Field("none", description=f"one of {', '.join(BODY_FORCES)}")
    value: list[float] = Field([0.0, 0.0, 0.0], description="vector or magnitude(s) at load factor 1 [N/m^3]")



class Loading(Strict):
    """The load path: increments of the load factor from 0 to `final`."""

    steps: int = Field(1, ge=1, description="number of equal increments")
    final: float = Field(1.0, description="final load factor [1]")
    factors: Optional[list[float]] = Field(None, description="explicit load factors (replaces steps/final)")
    max_cuts: int = Field(6, ge=0, le=30, description="step halvings allowed per increment")
    adaptive: bool = Field(False, description="grow the step after easy increments (one increment per launch); "
                           "the load factors above are still all reached and written")
    grow: float = Field(1.5, gt=1, le=4, description="step growth after an easy increment [1]")
    easy_iterations: int = Field(4, ge=1, description="Newton iterations at or below which an increment is easy")
    max_step: Optional[float] = Field(None, gt=0, description="largest load-factor step [1]; default the nominal step")

    def load_factors(self) -> list[float]:
        """The target load factors in order."""
        if self.factors:
            return [float(f) for f in self.factors]
        return [self.final * (i + 1) / self.steps for i in range(self.steps)]

    def nominal_step(self) -> float:
        """The smallest step between successive target load factors."""
        t = self.load_factors()
        return min(abs(b - a) for a, b in zip([0.0] + t[:-1], t)) or 1.0


class Petsc(Strict):
    """The PETSc solver (numerics.solver = "petsc"): CG + a preconditioner preset, PETSc options on top."""

    pc: PcName = Field("ml", description=f"preconditioner: {', '.join(PRECONDITIONERS)}")
    options: str = Field("", description="more PETSc options, \"-name value\" pairs (e.g. \"-ksp_rtol 1e-8\"); "
                         "they override the preset; no option that reads or writes files")
    reuse: bool = Field(True, description="keep the preconditioner across Newton steps and increments until "
                        "the iterations it costs beyond a fresh one's add up to a setup's cost in iterations "
                        "(PETSc option -wendel_pc_setup_its, default 20)")

    @field_validator("options")
    @classmethod
    def _options(cls, v):
        return check_options(v)


class Numerics(Strict):
    """Solver settings."""

    ranks: int = Field(1, ge=1, le=64, description="MPI ranks")
    solver: SolverName = Field("direct", description=f"linear solver: {', '.join(SOLVERS)}")
    direct: Literal["umfpack", "mumps"] = Field("umfpack", description="the direct solver's factorization: "
                                                 "umfpack (FreeFEM's UMFPACK64) or mumps (MUMPS's LU through "
                                                 "wendel's PETSc plugin; the same solution to round-off, faster "
                                                 "on F-bar's denser matrices: wendel bench direct)")
    solver_tol: float = Field(1e-10, gt=0, lt=1, description="relative residual of iterative solvers [1]")
    newton_tol: float = Field(1e-9, gt=0, lt=1, description="relative Newton residual [1] (a cutting "
                              "scene's FE cut: 1e-8 unless set)")
    forcing: Literal["fixed", "ew"] = Field("fixed", description="tolerance of the Newton steps' iterative "
                                            "solves (cg, petsc): fixed = solver_tol; ew = an inexact Newton, "
                                            "Eisenstat-Walker's forcing term (0.1 at most, no tighter than the "
                                            "Newton tolerance needs); the Newton tolerance is unchanged")
    newton_maxit: int = Field(25, ge=1, le=500, description="Newton iterations per increment")
    predictor: Literal["none", "extrapolate"] = Field("none", description="first guess of an increment: none = "
                                                      "the accepted state; extrapolate = plus the last increment's "
                                                      "displacement increment scaled to the load step (one Newton "
                                                      "iteration less on a smooth nonlinear path; "
                                                      "edp/lib/predictor.idp)")
    timeout: float = Field(3600.0, gt=0, description="wall-time limit of one FreeFEM launch [s]")
    petsc: Petsc = Field(default_factory=Petsc, description="PETSc solver settings (solver = \"petsc\")")
    assembly: AssemblyName = Field("freefem", description="tangent, internal forces and strains: freefem (the varf "
                                   "forms) or compiled (C++ element kernels: 3D P1 small-strain J2 plasticity)")
    max_elements: float = Field(3e6, gt=0, description="refuse a mesh estimated above this many elements before "
                                "meshing (about 1 GB per 300k 3D elements here; raise it on a bigger machine) [1]")
    max_increments: int = Field(100000, ge=1, description="refuse a load path of more increments than this [1]")


    @model_validator(mode="after")
    def _ranks(self):
        if self.ranks > 1 and self.solver not in ("ffddm", "petsc"):
            raise ValueError(f"solver {self.solver!r} runs on one rank; use solver = \"ffddm\" or \"petsc\" "
                             f"with ranks = {self.ranks}")
        if self.direct != "umfpack" and self.solver != "direct":
            raise ValueError(f"direct = {self.direct!r} chooses the direct solver's factorization: it needs "
                             f"solver = \"direct\", not {self.solver!r}")
        if self.forcing != "fixed" and self.solver not in ("cg", "petsc"):
            raise ValueError(f"forcing = {self.forcing!r} needs an iterative solver: solver = \"cg\" or \"petsc\"")
        return self


class Kinematics(Strict):
    """Small strain on the mesh of the last remesh, or updated-Lagrangian large deformation
    (edp/lib/kinematics.idp: incremental logarithmic strain, polar rotation of the increment; 2D plane strain,
    axisymmetric (r, z) or 3D, P1)."""

    kind: KinematicsName = Field("small-strain", description=f"one of {', '.join(KINEMATICS)}")
    min_area_ratio: float = Field(0.02, ge=0, lt=1, description="updated-Lagrangian: an increment that shrinks "
                                  "a cell's area below this ratio is refused as tangling (the step is cut) [1]")
    initial_strain: list[float] = Field([0.0, 0.0, 0.0], description="updated-Lagrangian: homogeneous initial "
                                        "strain [xx, yy, xy] (tensor components) of a prestressed body [1]")
    volumetric: Literal["cell", "fbar"] = Field("cell", description="updated-Lagrangian: the "
                                                "volume change of a P1 cell is its own (\"cell\"), or F-bar: the "
                                                "increment's volume change averaged over the vertex patches "
                                                "(\"fbar\"; against volumetric locking in plastic flow, "
                                                "edp/lib/kinematics-fbar.idp)")

    @field_validator("initial_strain")
    @classmethod
    def _initial(cls, v):
        if len(v) != 3:
            raise ValueError("initial_strain has 3 components [xx, yy, xy]")
        return v

    @property
    def updated_lagrangian(self) -> bool:
        return self.kind == "updated-lagrangian"


class Output(Strict):
    """What a run writes besides summary.json and the histories."""

    vtu: bool = Field(True, description="one VTU per increment and a PVD index")
    png: bool = Field(True, description="picture of the deformed body at the last increment")
    warp: float = Field(0.0, ge=0, description="displacement scale of the picture; 0 = automatic")


class RemeshZone(Strict):
    """A box of finer size for the new meshes, graded to remesh.h outside it (``wendel.remesh.mesher``)."""

    box: list[list[float]] = Field(..., min_length=2, max_length=2, description="lower and upper corner "
                                   "[[x, y(, z)], [x, y(, z)]] [m]")
    h: float = Field(..., gt=0, description="element size inside the box [m]")
    thickness: float = Field(0.0, ge=0, description="distance outside the box over which the size grows "
                             "linearly to remesh.h [m]")

    @field_validator("box")
    @classmethod
    def _box(cls, v):
        if any(len(c) not in (2, 3) or len(c) != len(v[0]) for c in v) or any(not abs(x) < 1e30 for c in v for x in c):
            raise ValueError(f"box: two corners of 2 or 3 finite coordinates, got {v}")
        if any(a > b for a, b in zip(*v)):
            raise ValueError(f"box: the lower corner must be below the upper one, got {v}")
        return v


class RemeshTrim(Strict):
    """Material the new meshes leave out (2D, ``wendel.remesh.mesher``): the cells whose centre lies farther than
    ``radius`` from ``point`` and above ``above``; of what is left, the largest connected body is meshed, its new
    edges labelled ``label``. For a chip that curls back onto the workpiece: its far end is cut off."""

    point: list[float] = Field(..., min_length=2, max_length=2, description="centre [x, y] [m] (with "
                               "remesh.zones_follow = tool, written for the tool at load factor 0 and moved with it)")
    radius: float = Field(..., gt=0, description="material farther than this from the point is left out [m]")
    above: float = Field(..., description="only material whose cell centre lies above this y [m]")
    label: str = Field(..., description="the boundary name the cut edges get (one of the mesh's boundaries)")

    @field_validator("point")
    @classmethod
    def _finite(cls, v):
        if any(not abs(x) < 1e30 for x in v):
            raise ValueError("remesh.trim.point: finite numbers")
        return v


class Remesh(Strict):
    """Remeshing of the deformed body (its presence enables it): when the deformed mesh's quality falls
    below the threshold, gmsh meshes the deformed configuration anew and the state is transferred."""

    min_quality: float = Field(0.1, gt=0, lt=1, description="remesh when the min SICN of the deformed mesh falls below [1]")
    h: Optional[float] = Field(None, gt=0, description="element size of the new meshes [m]; default geometry.h")
    h_min: Optional[float] = Field(None, gt=0, description="smallest size where the indicator peaks [m]; default h/3")
    indicator: str = Field("p", description="cell field that grades the size (e.g. p); empty: uniform size")
    max_remeshes: int = Field(20, ge=0, description="remeshes allowed in one run")
    at: list[int] = Field(default_factory=list, description="increments after which to remesh whatever the quality")
    on_failure: bool = Field(True, description="a step that fails even after loading.max_cuts halvings: remesh "
                             "the last converged increment and go on (once per mesh; when the first step on the new "
                             "mesh fails so, it is tried without the motion carried over, then the body meshed again "
                             "with other gmsh algorithms; false: stop there)")
    relax_steps: int = Field(1, ge=1, le=64, description="the re-equilibration after a remesh releases the "
                             "transferred state's out-of-balance forces in this many stages, each converged by "
                             "Newton (1: at once) [1]")
    relax_tol: Optional[float] = Field(None, gt=0, lt=1, description="relative residual at which a stage of the "
                                       "re-equilibration before the last hands on to the next, whatever the contact "
                                       "and friction sets do (the last stage converges as every increment) [1]; "
                                       "default numerics.newton_tol: each stage converged")
    first_step: float = Field(1.0, gt=0, le=1, description="the first forward step after a re-equilibration as a "
                              "share of the step to the next load factor, doubled up to it (0.25: 1/4, 1/4, 1/2 of "
                              "the step) [1]; 1: the whole step")
    zones: list[RemeshZone] = Field(default_factory=list, description="boxes of finer size [[remesh.zones]] "
                                    "(box, h, thickness), graded to remesh.h outside them")
    smooth_features: float = Field(0.0, ge=0, lt=0.5, description="2D: before meshing, drop old boundary nodes "
                                   "whose neighbours are closer than the local target size and that stand less than "
                                   "this share of it off their chord (wrinkles the new mesh cannot resolve; "
                                   "wendel.remesh.features) [1]; 0: keep every node")
    snap_to_tool: bool = Field(False, description="2D with a polygon tool (contact.tool): the new mesh's boundary "
                               "nodes that fall inside the tool (on old boundary edges that cut its rounded corner) "
                               "are moved onto its surface before the transfer (wendel.remesh.snap)")
    mesh_timeout: Optional[float] = Field(None, gt=0, description="seconds gmsh may take to mesh a deformed body: "
                                          "it then meshes in a worker process, stopped after that long, and the body "
                                          "is meshed with the next gmsh 2D algorithm (wendel.remesh.limit); default: "
                                          "gmsh in the driver's process, no limit")
    zones_follow: Literal["body", "tool"] = Field("body", description="body: the zones stand where they are "
                                                  "written; tool: they move with contact.path (written for "
                                                  "the tool at load factor 0)")
    trim: Optional[RemeshTrim] = Field(None, description="2D: material the new meshes leave out (remesh.trim: "
                                       "point, radius, above, label); it moves with the tool as the zones do")


class Reference(Strict):
    """What errors are measured against: an analytic field, errors a module computes against a closed
    form (record.json keys ``error_*``), or else the finest run of a study."""

    analytic: Optional[AnalyticName] = Field(
        None, description=f"analytic field: {', '.join(ANALYTIC_REFERENCES)}")
    errors: list[str] = Field(default_factory=list,
                              description="record.json keys of errors against closed forms, e.g. error_hertz_p0")
    quantity: str = Field("strain_energy", description="record.json quantity compared with the finest run")
    probe: Optional[list[float]] = Field(None, min_length=2, max_length=3, description="point whose "
                                         "displacement record.json gives as probe_ux, probe_uy(, probe_uz) [m]")
    compare: Optional[ComparisonName] = Field(
        None, description=f"another code's figures of the quantity, plotted by wendel study: {', '.join(COMPARISONS)}")


    @field_validator("probe")
    @classmethod
    def _probe(cls, v):
        if v is not None and not all(abs(c) < 1e30 for c in v):
            raise ValueError(f"probe: coordinates must be finite numbers below 1e30 in size, got {v}")
        return v

    @field_validator("errors")
    @classmethod
    def _errors(cls, v):
        bad = [k for k in v if not k.startswith("error_")]
        if bad:
            raise ValueError(f"error keys start with error_: {', '.join(bad)}")
        return v


class Smoke(Strict):
    """The tiny size every scene declares (`wendel run --smoke`, CI): overrides of geometry and loading."""

    model_config = ConfigDict(extra="forbid")
    h: Optional[float] = Field(None, gt=0, description="element size of the smoke run [m]")
    steps: Optional[int] = Field(None, ge=1, description="increments of the smoke run")
    ranks: Optional[int] = Field(None, ge=1, description="MPI ranks of the smoke run")


def _scene_model():
    load_all()
    extra = {name: (Optional[block.model], None) for name, block in BLOCKS.items()}
    return create_model(
        "Scene",
        __base__=SceneBase,
        **extra,
    )


class SceneBase(Strict):
    """A scene: a one-line description, then geometry, material, physics, loading, numerics, output."""

    description: str = Field(..., min_length=1, description="one line saying what is simulated")
    problem: str = Field("mechanics", description="mechanics (default) or a registered scalar problem")
    geometry: Geometry
    material: Optional[Material] = Field(None, description="required by mechanics")
    elasticity: Elasticity = Elasticity()
    boundary: dict[str, Boundary] = Field(default_factory=dict, description="conditions by boundary name")
    body_force: BodyForce = BodyForce()
    kinematics: Kinematics = Kinematics()
    loading: Loading = Loading()
    numerics: Numerics = Numerics()
    output: Output = Output()
    remesh: Optional[Remesh] = Field(None, description="present: remesh the deformed body when it distorts")
    reference: Reference = Reference()
    smoke: Smoke = Smoke()

    @model_validator(mode="after")
    def _consistency(self):
        if self.problem == "mechanics":
            if self.material is None:
                raise ValueError("material: Field required (problem = \"mechanics\", the default, needs it; "
                                 "a scalar problem is named by `problem`)")
            foreign = [n for n, b in BLOCKS.items() if not b.mechanics and getattr(self, n, None) is not None]
            if foreign:
                raise ValueError(f"table(s) {', '.join(foreign)} belong to another problem; set `problem`")
        elif self.problem not in PROBLEMS:
            raise ValueError(f"unknown problem {self.problem!r}; valid: mechanics, {', '.join(sorted(PROBLEMS))}")
        else:
            allowed = set(PROBLEMS[self.problem].tables)
            present = {name for name in BLOCKS if getattr(self, name, None) is not None}
            present |= {t for t in ("material",) if getattr(self, t) is not None}
            present |= {t for t in ("boundary",) if getattr(self, t)}
            extra = sorted(present - allowed)
            if extra:
                raise ValueError(f"problem {self.problem!r} does not use the table(s) {', '.join(extra)}")
        for name, block in BLOCKS.items():
            if block.check is not None and getattr(self, name, None) is not None:
                block.check(getattr(self, name), self)
        if self.kinematics.updated_lagrangian:
            if self.problem != "mechanics":
                raise ValueError("kinematics.kind = \"updated-lagrangian\" is for mechanics scenes")
            th = getattr(self, "thermal", None)
            if th is not None and th.source_kind in ("manufactured", "moving"):
                raise ValueError(f"kinematics.kind = \"updated-lagrangian\" is not implemented with a {th.source_kind} "
                                 "heat source (its position and exact fields are those of the launch mesh)")
            if self.elasticity.plane == "stress":
                raise ValueError("kinematics.kind = \"updated-lagrangian\" needs elasticity.plane = \"strain\" "
                                 "or \"axisymmetric\"")
        elif self.kinematics.initial_strain != [0.0, 0.0, 0.0]:
            raise ValueError("kinematics.initial_strain needs kinematics.kind = \"updated-lagrangian\"")
        elif self.kinematics.volumetric != "cell":
            raise ValueError("kinematics.volumetric needs kinematics.kind = \"updated-lagrangian\"")
        if self.body_force.kind == "manufactured" and self.reference.analytic is None:
            raise ValueError("body_force.kind = \"manufactured\" needs reference.analytic")
        if self.remesh is not None and self.remesh.zones_follow == "tool" and \
                getattr(getattr(self, "contact", None), "path", None) is None:
            raise ValueError("remesh.zones_follow = \"tool\" needs a moving tool (contact.path)")
        if self.remesh is not None and self.remesh.snap_to_tool:
            check_snap(getattr(self, "contact", None))
        check_kernels(self)                # numerics.assembly = "compiled" against the other tables
        if self.problem == "mechanics":
            check_axisymmetric(self)       # elasticity.plane/order/reference against the other tables
        return self

    @property
    def blocks(self) -> list[str]:
        """Names of the optional physics blocks present, in entry-script order (mechanics only)."""
        if self.problem != "mechanics":
            return []
        return sorted(n for n, b in BLOCKS.items() if b.mechanics and getattr(self, n, None) is not None)


Scene = _scene_model()


def check_snap(contact) -> None:
    """``remesh.snap_to_tool`` is for what :mod:`wendel.remesh.snap` handles: a rigid 2D polygon tool
    (``contact.tool.vertices``) that is convex (the snap's closest points assume convex corners) and only
    translates (no ``contact.path.angle``); anything else refused by key rather than snapped by nothing."""
    tool = getattr(contact, "tool", None) if getattr(contact, "obstacle", None) == "tool" else None
    if tool is None or tool.vertices is None:
        raise ValueError("remesh.snap_to_tool needs a 2D polygon tool (contact.obstacle = \"tool\" with "
                         "contact.tool.vertices); this scene has none")
    v = tool.vertices
    for k in range(len(v)):
        a, b, c = v[k - 1], v[k], v[(k + 1) % len(v)]
        if (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]) < 0:
            raise ValueError(f"remesh.snap_to_tool handles convex tools; contact.tool.vertices[{k}] is a reflex corner")
    path = getattr(contact, "path", None)
    if path is not None and any(a != 0 for a in (path.angle or [])):
        raise ValueError("remesh.snap_to_tool is for a tool that only translates; contact.path.angle turns it")


def _describe(model: type[BaseModel], prefix: str) -> list[tuple[str, str, str, str]]:
    rows = []
    for name, f in model.model_fields.items():
        ann = f.annotation
        if isinstance(ann, type) and issubclass(ann, BaseModel):
            rows += _describe(ann, f"{prefix}{name}.")
            continue
        args = getattr(ann, "__args__", ())
        sub = [a for a in args if isinstance(a, type) and issubclass(a, BaseModel)]
        if sub:   # an optional table, or a dict of tables such as boundary.<name>
            named = typing.get_origin(ann) is dict
            rows += _describe(sub[0], f"{prefix}{name}.{'<name>.' if named else ''}")
            continue
        rng = ", ".join(f"{type(m).__name__.lower()} {getattr(m, type(m).__name__.lower(), '')}"
                        for m in f.metadata if type(m).__name__ in ("Gt", "Ge", "Lt", "Le"))
        inner = [typing.get_args(a)[0] if typing.get_origin(a) is typing.Annotated else a
                 for a in args if a is not type(None)]
        if getattr(ann, "__name__", "") == "Literal" or str(ann).startswith("typing.Literal"):
            typ = " \\| ".join(repr(a) for a in args)
        elif type(None) in args and inner:
            typ = getattr(inner[0], "__name__", str(inner[0])) + ", optional"
        elif typing.get_origin(ann) is typing.Union:
            typ = " or ".join(getattr(a, "__name__", str(a)) for a in inner)
        else:
            typ = getattr(ann, "__name__", str(ann))
        default = "required" if f.is_required() else repr(f.default) if f.default_factory is None else "{}"
        rows.append((prefix + name, typ, default, (f.description or "") + (f" ({rng})" if rng else "")))
    return rows


KEYS_BEGIN, KEYS_END = "<!-- scene keys: begin (wendel keys --update README.md) -->", "<!-- scene keys: end -->"


def update_readme(path) -> bool:
    """Replace the key table between the markers of ``path``; return whether it changed."""
    from pathlib import Path

    text = Path(path).read_text()
    head, rest = text.split(KEYS_BEGIN, 1)
    _, tail = rest.split(KEYS_END, 1)
    new = f"{head}{KEYS_BEGIN}\n{keys_table()}\n{KEYS_END}{tail}"
    if new != text:
        Path(path).write_text(new)
    return new != text


def keys_table() -> str:
    """The scene keys as a Markdown table (the README's table is this text; a test keeps them equal)."""
    from ..meshes.params import keyword_rows

    rows = _describe(Scene, "")
    at = next(i for i, r in enumerate(rows) if r[0].startswith("geometry.")) + 1
    rows[at:at] = keyword_rows()      # the builders' keywords after geometry.builder
    lines = ["| key | type | default | meaning |", "|---|---|---|---|"]
    lines += [f"| `{k}` | {t} | {d} | {m} |" for k, t, d, m in rows]
    return "\n".join(lines)
