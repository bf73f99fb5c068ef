"""What one FreeFEM launch of a scene gets: the entry script, its -D macros, its -key value options, the tables.

The mechanics family has one entry script, ``edp/mechanics.edp``; which modules it compiles is chosen by
``-D`` macros after the script name (``-Ddimension=2 -DPk=P1 -DWITHPLASTICITY=1``): each block of the
scene declares its macro (``Block.macro``), and a block the scene does not name is not compiled. Other
problems (:class:`wendel.scene.blocks.Problem`) name their own entry script and macros.
"""

from __future__ import annotations

from ..meshes import LABELS
from ..scene import kernels, petsc
from ..scene import axisymmetric
from ..scene.blocks import BLOCKS, PROBLEMS, discretization
from ..scene.blocks.contact import in_current_configuration
from ..scene.schema import ANALYTIC_REFERENCES, BODY_FORCES, Scene
from .checkpoint import RunFiles


ELEMENT = "P1"
"""The scalar Lagrange element of the mechanics entry (``-DPk=``); P1 for every scene today."""


def entry_script(scene: Scene, dimension: int) -> str:
    """The entry script of the scene's problem (``mechanics.edp`` for the mechanics family)."""
    if scene.problem != "mechanics":
        return PROBLEMS[scene.problem].entry(scene, dimension)
    return "mechanics.edp"


def macros(scene: Scene, dimension: int) -> list[str]:
    """The ``-D`` arguments of the launch: which code FreeFEM compiles.

    Mechanics: the dimension, the element and the macro of each block the scene names (a block without
    one, or one the scene does not name, adds nothing: FreeFEM's ``IFMACRO`` tests whether a macro is
    defined, not its value, so a module that is off is left out rather than passed as 0).

    >>> from wendel.freefem import ROOT
    >>> from wendel.scene import load
    >>> macros(load(ROOT / "workflows" / "smoke.toml"), 2)
    ['-Ddimension=2', '-DPk=P1']
    >>> macros(load(ROOT / "workflows" / "ball-indent.toml"), 3)
    ['-Ddimension=3', '-DPk=P1', '-DWITHCONTACT=1', '-DWITHPLASTICITY=1', '-DWITHPETSC=1', '-DWITHKERNELS=1']
    >>> macros(load(ROOT / "workflows" / "sliding-block.toml"), 2)[-1]
    '-DWITHFRICTION=1'
    """
    if scene.problem != "mechanics":
        return [f"-D{m}=1" for m in PROBLEMS[scene.problem].macros]
    element = discretization.element(scene) or axisymmetric.element(scene, dimension) or ELEMENT
    switches = [f"-Ddimension={dimension}", f"-DPk={element}"]
    switches += discretization.macros(scene)       # -DWITHDG=1: edp/lib/dg.idp
    switches += [f"-D{BLOCKS[name].macro}=1" for name in scene.blocks if BLOCKS[name].macro]
    # a switch that depends on a key rather than on a block goes here: switches.append("-DNAME=1") when on
    switches += axisymmetric.macros(scene, dimension)
    if scene.kinematics.updated_lagrangian:
        switches.append("-DUPDATEDLAGRANGIAN=1")     # edp/lib/kinematics.idp
    if getattr(scene, "contact", None) is not None and in_current_configuration(scene.contact, scene):
        switches.append("-DWITHFRICTION=1")      # friction, tool, path or force control: edp/lib/friction.idp
    if scene.numerics.solver == "petsc":
        switches.append("-DWITHPETSC=1")       # loads wendel's PETSc plugin (lib/petsc.idp)
    if scene.numerics.direct == "mumps":        # (the scene check ties it to solver = "direct")
        switches.append("-DWITHPETSCLU=1")     # MUMPS's LU through the same plugin (lib/solver.idp)
    switches += kernels.macros(scene, dimension)     # -DWITHKERNELS=1: compiled element kernels (lib/kernels.idp)
    return switches


def options(scene: Scene, files: RunFiles, dimension: int, segment: dict | None = None) -> list[str]:
    """FreeFEM options of the scene: numbers and integer ids only (and file paths the driver made)."""
    n = scene.numerics
    segment = segment or {"mesh": "mesh.msh", "ubase": None, "eps0": None}
    opts = ["-mesh", str(files.root / segment["mesh"]), "-solver", n.solver, "-solver_tol", repr(n.solver_tol),
            "-newton_tol", repr(n.newton_tol), "-newton_maxit", str(n.newton_maxit)]
    if n.forcing != "fixed":
        opts += ["-solver_forcing", n.forcing]
    if n.predictor == "extrapolate":
        opts += ["-newton_predictor", "1"]     # edp/lib/predictor.idp
    if scene.remesh and scene.remesh.relax_tol:        # read by a re-equilibration's launch (-relax_steps)
        opts += ["-relax_tol", repr(scene.remesh.relax_tol)]
    if n.solver == "petsc":
        opts += petsc.launch_options(n.petsc.pc, n.petsc.options, n.petsc.reuse)
    if scene.problem != "mechanics":
        return opts + PROBLEMS[scene.problem].options(scene, files, dimension)
    m = scene.material
    opts += ["-mat_E", repr(m.E), "-mat_nu", repr(m.nu),
             "-el_plane_stress", "1" if scene.elasticity.plane == "stress" else "0",
             "-bc", str(files.tables / "bc.txt"), "-trac", str(files.tables / "trac.txt")]
    opts += axisymmetric.options(scene, dimension)
    for key in ("ubase", "eps0"):      # updated Lagrangian: the strain is state (ul_eps.qp.txt), no pre-strain
        if segment.get(key) and not (key == "eps0" and scene.kinematics.updated_lagrangian):
            opts += [f"-{key}", str(files.root / segment[key])]
    if (files.tables / "motion.txt").is_file():
        opts += ["-bc_motion", str(files.tables / "motion.txt")]
    opts += kinematics_options(scene)
    bf = scene.body_force
    v = list(bf.value) + [0.0] * (3 - len(bf.value))
    opts += ["-body_id", str(BODY_FORCES[bf.kind]), "-body_fx", repr(v[0]), "-body_fy", repr(v[1]),
             "-body_fz", repr(v[2])]
    if scene.reference.probe:
        opts += [v for a, c in zip("xyz", scene.reference.probe) for v in (f"-probe_{a}", repr(float(c)))]
    if scene.reference.analytic:
        opts += ["-ref_id", str(ANALYTIC_REFERENCES[scene.reference.analytic])]
    for name in scene.blocks:
        opts += BLOCKS[name].options(getattr(scene, name), scene, files)
    return opts


def kinematics_options(scene: Scene) -> list[str]:
    """Updated-Lagrangian kinematics (edp/lib/kinematics.idp, compiled by the -D switch of :func:`macros`)."""
    k = scene.kinematics
    if not k.updated_lagrangian:
        return []
    e = k.initial_strain
    return ["-ul_min_jacobian", repr(k.min_area_ratio), "-ul_volumetric", str(int(k.volumetric == "fbar")),
            "-ul_eps_xx", repr(e[0]), "-ul_eps_yy", repr(e[1]), "-ul_eps_xy", repr(e[2])]


def write_tables(scene: Scene, files: RunFiles, dimension: int) -> None:
    """Boundary condition tables for bc.idp (labels from meshes/labels.py)."""
    files.tables.mkdir(parents=True, exist_ok=True)
    dirichlet, neumann, motion = [], [], []
    for name, b in scene.boundary.items():
        lab = LABELS[name]
        if b.motion:
            g = b.gradient or [0.0] * 4
            motion.append(f"{lab} " + " ".join(repr(float(v)) for v in [b.rotation or 0.0, *g, *b.center]))
        for comp, val in enumerate((b.ux, b.uy, b.uz)):
            if val is not None:
                if comp == 2 and dimension == 2:
                    raise ValueError(f"boundary.{name}.uz: a 2D scene has no z component")
                dirichlet.append(f"{lab} {comp} {val!r}")
        if b.traction is not None or b.pressure is not None:
            t = list(b.traction or [0.0, 0.0]) + [0.0] * 3
            neumann.append(f"{lab} {t[0]!r} {t[1]!r} {t[2]!r} {float(b.pressure or 0.0)!r}")
    (files.tables / "bc.txt").write_text(f"{len(dirichlet)}\n" + "".join(r + "\n" for r in dirichlet))
    (files.tables / "trac.txt").write_text(f"{len(neumann)}\n" + "".join(r + "\n" for r in neumann))
    if motion:
        (files.tables / "motion.txt").write_text(f"{len(motion)}\n" + "".join(r + "\n" for r in motion))
