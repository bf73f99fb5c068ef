"""The finite-element cut of a ``[cutting]`` scene: the mechanics scene that ``wendel run`` solves.

A cutting scene describes the process (``[cutting]``), the work material (``[plasticity]``, Johnson-Cook)
and the workpiece (``orthogonal-cutting`` builder). :func:`fe_scene` turns it into a plain mechanics scene
of modules that exist and are tested on their own:

- updated-Lagrangian kinematics, 2D plane strain (``edp/lib/kinematics.idp``);
- the tool as a rigid rounded polygon (rake face, edge radius, flank face; ``edp/lib/tool.idp``) moving
  in -x by ``cutting.cut_length`` over the load factor 0 -> 1, Coulomb friction ``cutting.friction`` on
  the whole ``free_surface`` (top of the layer and the step face; ``edp/lib/friction.idp``), capped at
  ``cutting.shear_cap`` when given;
- Johnson-Cook plasticity with its rate term (time per unit load factor = cut length / speed) and its
  thermal softening. ``thermal.coupling = "adiabatic"``: the temperature is an internal variable of the
  quadrature points heated by beta (Taylor-Quinney) of the plastic work (``edp/lib/thermal.idp``'s
  adiabatic coupling); ``"staggered"`` or ``"monolithic"``: the heat equation on the current body
  (``edp/lib/kinematics-thermal.idp``; no advection term: the mesh moves with the material) with the same
  Taylor-Quinney heat and the rake face's frictional heat, ``cutting.heat_to_chip`` of the frictional work
  into the chip (``cutting.frictional_heat``; the rest goes to the rigid tool, which is not meshed, and leaves
  the model), every boundary insulated unless ``[thermal.boundary]`` says otherwise. k and c are constant
  (:func:`properties`); thermal expansion is left out (alpha = 0);
- a remesh of the deformed body every ``cutting.remesh_every`` increments (and whenever the element
  quality falls below 0.1), uniform size ``geometry.fine * geometry.h`` or, with ``cutting.edge_size``,
  graded from that size at the edge (:func:`size_zones`), with transfer of the UL state
  (``ul_eps``) and the plastic state (``wendel.remesh``).

**Units.** The FE scene is written in mm, MPa, N, s and K (forces per unit width in N/mm, energy mJ, so
rho c in mJ/mm^3/K = 1e-6 J/m^3/K and k unchanged): FreeFEM refuses
meshes with element areas below 1e-8 ("bug : mes < 1e-8 !", measured: a 25 um element is 6e-10 m^2).
:func:`forces` converts back to N for the width b.

No material separation criterion: the material splits at the rounded edge by flowing around it (the
stagnation point), and the mesh follows through remeshing (the DEFORM / PFEM way, issue 17 item 2).

>>> from wendel.freefem import ROOT
>>> from wendel.scene import load
>>> fe = fe_scene(load(ROOT / "workflows" / "cutting-aisi1045.toml", smoke=True))
>>> fe.kinematics.kind, fe.contact.obstacle, fe.contact.friction.mu, fe.geometry.model_extra["uncut"]
('updated-lagrangian', 'tool', 0.5, 0.15)
"""

from __future__ import annotations

import inspect
import math

import numpy as np

from ..meshes.cutting import orthogonal_cutting
from ..remesh.batch import ramp
from ..scene.blocks.cutting import FE_NUMERICS
from ..scene.schema import Scene
from .tool import tool_polygon

MM = 1e3          # m -> mm
TRIM_ABOVE = 1.05  # cutting.trim_chip: only material above the uncut layer's top (h above the tip) and a little more
MPA = 1e-6        # Pa -> MPa
GAP = 0.02        # the tool starts this fraction of h in front of the step face
RELAX_STEPS = 4   # the re-equilibration after a remesh releases the transferred out-of-balance in 4 stages
# F-bar's first forward step on a new mesh: 1/4, 1/4, 1/2 of the step (cutting.first_step; session 24: on the 1.2 mm
# r/2 cut with conduction it converged at 1/16 (7 of 51 remeshes), 1/8 (19), 1/4 (20) or 1/2 (5) of the step after
# 1-4 failed tries; the P1 cells' cut takes its whole steps there: 17 increments, 31 with this, on the smoke cut)
FIRST_STEP_FBAR = 0.25
# F-bar's chip front folds where it meets the uncut surface ahead (notches 3-5 um deep, 0.4 mm ahead of the tool):
# its remeshes drop boundary nodes standing less than a quarter of the new size off their neighbours' chord (fresh
# meshes' minimum quality 0.57-0.65 instead of 0.08-0.16 from 665 um on, measured; remesh.smooth_features)
SMOOTH_FBAR = 0.25
EDGE_ZONE = 2.0   # graded remesh (cutting.edge_size): the edge box reaches 2 edge radii from the edge's centre
GROWTH = 0.3      # ... the size grows by 0.3 per unit distance outside a zone
FAR = 2.0         # ... and is 2 geometry.fine * geometry.h far from the tool
# gmsh may take this long to mesh the deformed body (remesh.mesh_timeout; a cut's remesh takes 0.1-0.2 s, measured;
# session 27: the titanium cut's remesh 162 hung in gmsh for 11 minutes), then the next gmsh 2D algorithm meshes it
MESH_TIMEOUT = 60.0


def tool_at_start(cutting, x_step: float) -> dict:
    """The tool polygon in mm at load factor 0: sharp vertices (rake top, edge, flank end, back) with the
    edge radius as the corner radius of the edge vertex, its lowest point on the machined level y = 0 and
    its leftmost point inside the layer ``GAP * h`` in front of the step face at ``x_step`` [mm].
    Also the tip (lowest point) and the rake direction, for the outputs."""
    h, r = cutting.uncut_thickness * MM, cutting.edge_radius * MM
    rake, clearance = math.radians(cutting.rake), math.radians(cutting.clearance)
    sharp = tool_polygon(rake, clearance, 0.0, (cutting.rake_length or 6 * cutting.uncut_thickness) * MM,
                         (cutting.flank_length or 4 * cutting.uncut_thickness) * MM).vertices
    t_rake = np.array([math.sin(rake), math.cos(rake)])
    t_flank = np.array([math.cos(clearance), math.sin(clearance)])
    wedge = math.pi / 2 - rake - clearance
    bisector = (t_rake + t_flank) / np.linalg.norm(t_rake + t_flank)
    centre = bisector * r / math.sin(wedge / 2) if r > 0 else np.zeros(2)
    lowest = centre[1] - r if r > 0 else 0.0
    x_rake_at_h = (h - (-lowest)) * t_rake[0] / t_rake[1]          # the rake face (through the origin) at y = h
    left = min(centre[0] - r, x_rake_at_h) if r > 0 else min(0.0, x_rake_at_h)
    shift = np.array([x_step + GAP * h - left, -lowest])
    radii = [0.0] * len(sharp)
    radii[1] = r
    tip = (centre + shift - [0.0, r]) if r > 0 else shift
    return {"vertices": (sharp + shift).tolist(), "radii": radii, "tip": tip.tolist(),
            "rake_dir": t_rake.tolist(), "edge": (shift + [0.0, 0.0]).tolist()}


def size_zones(cutting, tip, h_mid: float, travel: float) -> list[dict]:
    """The remeshes' size zones [mm] for the tool at load factor 0 (they follow the tool): ``cutting.edge_size``
    in a box around the edge (half-width ``EDGE_ZONE`` edge radii, at least 4 edge sizes), ``h_mid`` in a box
    over the primary shear zone, the chip root and the rake contact (3 h ahead of the edge to 2 h behind it,
    h below to 3.5 h above the tip), each reaching ahead by the ``travel`` until the next remesh (the tool
    must still be in them then), each graded by ``GROWTH`` (size per unit distance) to the size outside it
    (``FAR`` h_mid far away). Written for the tool at the tip ``tip`` [mm]."""
    h, r, s = cutting.uncut_thickness * MM, cutting.edge_radius * MM, cutting.edge_size * MM
    x, y = tip
    a = max(EDGE_ZONE * r, 4 * s)
    cy = y + r
    return [{"box": [[x - a - travel, cy - a], [x + a, cy + a]], "h": s, "thickness": max(h_mid - s, 0.0) / GROWTH},
            {"box": [[x - 3 * h - travel, y - h], [x + 2 * h, y + 3.5 * h]], "h": h_mid,
             "thickness": (FAR - 1) * h_mid / GROWTH}]


def fe_scene(scene, travel: float = 1.0) -> Scene:
    """The mechanics scene (mm, MPa, N) of the FE cut of a validated cutting scene; ``travel`` scales the
    cut length (a smoke run is the first increments of the full cut: its steps over the full steps)."""
    c, g = scene.cutting, scene.geometry
    extra = dict(g.model_extra or {})
    length_keys = ("length", "depth", "uncut", "pre_cut")
    geometry = {"builder": g.builder, "h": g.h * MM, **{k: v for k, v in extra.items() if k not in length_keys}}
    for k in length_keys:
        if k in extra:
            geometry[k] = float(extra[k]) * MM
    defaults = {k: q.default for k, q in inspect.signature(orthogonal_cutting).parameters.items()
                if q.default is not inspect.Parameter.empty}      # the builder's, for keys the scene leaves out
    length = float(extra.get("length", defaults["length"])) * MM
    pre_cut = float(extra.get("pre_cut", defaults["pre_cut"])) * MM
    fine = float(extra.get("fine", defaults["fine"]))
    tool = tool_at_start(c, length - pre_cut)
    cut = travel * (c.cut_length if c.cut_length is not None else 2 * c.uncut_thickness) * MM
    p = scene.plasticity
    plasticity = {"law": "johnson-cook", "jc_A": p.jc_A * MPA, "jc_B": p.jc_B * MPA, "jc_n": p.jc_n,
                  "jc_C": p.jc_C, "jc_rate0": p.jc_rate0, "jc_m": p.jc_m, "jc_T_room": p.jc_T_room,
                  "jc_T_melt": p.jc_T_melt, "load_time": cut / MM / c.speed}
    friction = {"law": "coulomb", "mu": c.friction, "frame": c.friction_frame,
                "residual": c.friction_residual, "trace": c.friction_trace}
    if c.shear_cap is not None:
        friction["tau_max"] = c.shear_cap * MPA
    steps = scene.loading.steps
    every = c.remesh_every
    # the re-equilibration after a remesh is an increment too, and so are the first steps' shares (first): the
    # k-th remesh follows increment every + (k - 1) (every + 1 + n) (a step cut shifts the later ones by one
    # increment, and adds one: the list runs on to 3 times the steps, or a cut with many step cuts ran out of
    # scheduled remeshes at 70 % of its travel, measured at edge size r/4)
    first = c.first_step or (FIRST_STEP_FBAR if c.volumetric == "fbar" else 1.0)
    n = len(ramp(first))
    at = [every + (k - 1) * (every + 1 + n) for k in range(1, 3 * steps // every + 1)] if every else []
    # uniform size fine * h (graded on p down to half of it at the edge, the isothermal cut stopped at 40 um
    # instead of 92.5, measured: "mesh would invert" after the second remesh)
    remesh = {"at": at, "indicator": "", "h": fine * g.h * MM, "max_remeshes": len(at) + 20,
              "relax_steps": RELAX_STEPS, "relax_tol": c.relax_tol, "first_step": first, "mesh_timeout": MESH_TIMEOUT}
    smooth = c.smooth_features if c.smooth_features is not None else (SMOOTH_FBAR if c.volumetric == "fbar" else 0.0)
    if smooth > 0:
        remesh["smooth_features"] = smooth
    if c.snap_to_tool:
        remesh["snap_to_tool"] = True
    if c.trim_chip is not None:      # the chip's far end cut off (a chip that curls back onto the workpiece)
        remesh["trim"] = {"point": list(tool["tip"]), "radius": c.trim_chip * c.uncut_thickness * MM,
                          "above": tool["tip"][1] + TRIM_ABOVE * c.uncut_thickness * MM, "label": "free_surface"}
        remesh["zones_follow"] = "tool"
    if c.edge_size is not None:      # graded: fine at the edge, coarse far away (size_zones)
        remesh["h"] = FAR * fine * g.h * MM
        remesh["zones"] = size_zones(c, tool["tip"], fine * g.h * MM, (every or 1) * cut / steps)
        remesh["zones_follow"] = "tool"
        # the first mesh too: the old boundary's chords at the edge (25 um on a 20 um edge radius) put the fine
        # new boundary nodes up to 6 um inside the tool, and the first re-equilibration failed (measured)
        geometry["refine"] = remesh["zones"][0]
    boundary = {}
    for name, b in scene.boundary.items():
        d = b.model_dump(exclude_none=True)
        for key in ("ux", "uy"):
            if key in d:
                d[key] = d[key] * MM
        boundary[name] = d
    data = {
        "description": f"FE cut (mm, MPa, N): {scene.description}",
        "geometry": geometry,
        "material": {"E": scene.material.E * MPA, "nu": scene.material.nu},
        "elasticity": {"plane": "strain"},
        "plasticity": plasticity,
        "kinematics": {"kind": "updated-lagrangian", "volumetric": c.volumetric},
        "boundary": boundary,
        "contact": {"boundary": "free_surface", "normal": "+y", "obstacle": "tool",
                    "tool": {"vertices": tool["vertices"], "radii": tool["radii"]}, "friction": friction,
                    "path": {"load_factors": [0.0, 1.0], "x": [0.0, -cut], "y": [0.0, 0.0]}},
        "loading": {"steps": steps, "max_cuts": scene.loading.max_cuts},
        # newton_maxit: room for the contact and friction sets to settle in a re-equilibration (40 stopped one
        # at 55 um when the adiabatic temperature was still a fixed point outside the tangent; since session 8
        # the return mapping solves it, plasticity.idp's plastAd)
        # predictor: each increment starts from the last one's motion extrapolated (the tool moves steadily; the
        # first guess from u_n met the tool 5 um deep: 30-40 % fewer Newton iterations, measured in session 8)
        # direct: the scene's factorization (numerics.direct = "mumps": MUMPS, faster on F-bar's denser matrix)
        # newton_tol 1e-8; the scene's numerics.direct, newton_tol and timeout where it sets them (FE_NUMERICS)
        "numerics": {"solver": "direct", "newton_tol": 1e-8, "newton_maxit": 100, "predictor": "extrapolate",
                     **scene.numerics.model_dump(include=FE_NUMERICS, exclude_unset=True)},
        "output": {"png": False, "vtu": True},
        "remesh": remesh,
    }
    th = scene.thermal
    if th is not None:
        k, cap = properties(scene)
        # adiabatic: heating by plastic work at the quadrature points; monolithic / staggered: the heat equation
        # on the current body (kinematics-thermal.idp), every boundary insulated unless [thermal.boundary] says
        # otherwise (the heat of a 0.1-0.2 ms cut diffuses sqrt(a t) ~ 40-60 um, the block is 0.5 mm deep)
        data["thermal"] = {"k": k, "rho": th.rho * 1e-6, "c": cap, "alpha": 0.0, "T_ref": th.T_ref,
                           "beta": th.beta, "coupling": th.coupling, "duration": plasticity["load_time"],
                           "staggered_softening": th.staggered_softening}
        if th.T_initial is not None:
            data["thermal"]["T_initial"] = th.T_initial
        if th.coupling != "adiabatic":
            data["thermal"]["boundary"] = {name: _heat_boundary(b) for name, b in th.boundary.items()}
            # the frictional work of the rake face: heat_to_chip of it into the chip, the rest into the tool, which
            # is rigid and not meshed (it leaves the model: friction_heat_tool in record.json)
            friction["heat_fraction"] = c.heat_to_chip if c.frictional_heat is not False else 0.0
    return Scene.model_validate(data)


def properties(scene) -> tuple[float, float]:
    """k [W/m/K] and c [J/kg/K] of the FE cut's heat equation: constant, at ``cutting.fe_properties_T`` from
    thermal.k, thermal.c and the slopes, or as written.

    >>> from wendel.freefem import ROOT
    >>> from wendel.scene import load
    >>> s = load(ROOT / "workflows" / "cutting-aisi1045.toml")
    >>> properties(s)
    (52.61, 420.0)
    >>> s.cutting.fe_properties_T = 773.15      # 500 C: Lalwani et al.'s k = 52.61 - 0.0281 T, c = 420 + 0.504 T
    >>> [round(v, 3) for v in properties(s)]
    [38.56, 672.0]
    """
    c, th = scene.cutting, scene.thermal
    if c.fe_properties_T is None:
        return th.k, th.c
    dT = c.fe_properties_T - c.properties_T0
    return th.k + c.k_slope * dT, th.c + c.c_slope * dT


def _heat_boundary(b) -> dict:
    """A [thermal.boundary] condition in the FE scene's units (mm: a flux W/m^2 = 1e-3 mW/mm^2)."""
    d = b.model_dump(exclude_none=True)
    for key in ("flux", "h"):
        if key in d:
            d[key] = d[key] * 1e-3
    return d


def forces(record: dict, width: float) -> tuple[float, float]:
    """Cutting and thrust force [N] on the tool of width ``width`` [m] from a record of the FE scene (the
    tool's force on the body, N/mm, is ``contact_force_x/y``; the body's on the tool is its opposite)."""
    b = width * MM
    return -float(record["contact_force_x"]) * b, -float(record["contact_force_y"]) * b
