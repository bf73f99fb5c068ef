"""The ``[cutting]`` block: an orthogonal cut (process, tool, and what the analytic model needs).

The table describes the cut (speed, uncut chip thickness, width), the tool (rake and clearance angles,
edge radius, face lengths), the rake-face contact (Coulomb friction, shear cap, heat partition) and the
temperature slopes of k and c that the extended Oxley model uses (:mod:`wendel.cutting.oxley`). The
material comes from the scene's other tables: Johnson-Cook constants from ``[plasticity]`` (law
``johnson-cook``), density, conductivity and heat capacity from ``[thermal]`` (at ``properties_T0``).

``wendel oxley SCENE.toml`` runs the analytic model from these tables. The finite-element chip
formation: ``wendel run`` of a cutting scene solves the mechanics scene that :mod:`wendel.cutting.fe`
derives from it (updated-Lagrangian kinematics, frictional polygon tool, Johnson-Cook with adiabatic heating
or heat conduction and frictional heat, remeshing; :data:`FE_READY`).

>>> c = Cutting(speed=200 / 60, uncut_thickness=0.15e-3, width=1.6e-3, rake=-7.0)
>>> c.clearance, c.oxley.properties
(7.0, 'chip')
"""

from __future__ import annotations

from typing import Literal, Optional

from pydantic import BaseModel, ConfigDict, Field, model_validator

from . import Block, choice, register

FE_READY = True
"""Whether the finite-element chip formation exists (:mod:`wendel.cutting.fe`)."""

PROPERTY_TEMPERATURES = ("shear-plane", "chip", "interface")
PropertyTemperature = choice(PROPERTY_TEMPERATURES, "property temperature")


class OxleyConstants(BaseModel):
    """Constants of the extended Oxley model (Oxley 1989; Lalwani, Mehta and Jain 2009)."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    eta: float = Field(0.9, gt=0, le=1, description="shear plane temperature T_AB = T_w + eta dT_sz [1]")
    psi: float = Field(0.9, gt=0, le=1, description="tool-chip interface temperature T_int = T_w + dT_sz + "
                       "psi dT_M [1]")
    properties: PropertyTemperature = Field(
        "chip", description="temperature of the chip's k and c in the secondary zone: shear-plane (T_AB), "
        "chip (mean chip temperature) or interface (T_int)")


class Cutting(BaseModel):
    """An orthogonal cut: plane strain, a rigid tool moving at ``speed`` through a layer ``uncut_thickness``."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    speed: float = Field(..., gt=0, description="cutting speed V [m/s] (200 m/min = 3.333 m/s)")
    uncut_thickness: float = Field(..., gt=0, description="uncut chip thickness h (feed) [m]")
    width: float = Field(..., gt=0, description="width of cut b (forces are reported for it) [m]")
    rake: float = Field(..., gt=-45, lt=45, description="rake angle, positive when the rake face leans away "
                        "from the chip [deg]")
    clearance: float = Field(7.0, gt=0, lt=45, description="clearance angle of the flank face [deg]")
    edge_radius: float = Field(0.0, ge=0, description="cutting edge radius r [m]; 0 = sharp")
    rake_length: Optional[float] = Field(None, gt=0, description="length of the tool's rake face [m]; default "
                                         "6 uncut_thickness")
    flank_length: Optional[float] = Field(None, gt=0, description="length of the tool's flank face [m]; "
                                          "default 4 uncut_thickness")
    friction: float = Field(0.5, ge=0, description="Coulomb coefficient on the rake face [1] (FE; Merchant's "
                            "and Lee-Shaffer's shear angles from atan of it)")
    shear_cap: Optional[float] = Field(None, gt=0, description="cap of the friction shear stress [Pa] (FE); "
                                       "default the chip's shear flow stress")
    heat_to_chip: float = Field(0.5, ge=0, le=1, description="share of the frictional heat that enters the "
                                "chip, the rest the tool [1] (FE)")
    friction_frame: Literal["compiled", "freefem", "check"] = Field(
        "compiled", description="FE: the Newton matrix's change to the contact nodes' local frames, as "
        "contact.friction.frame (compiled, freefem or check)")
    friction_residual: Literal["compiled", "freefem", "check"] = Field(
        "compiled", description="FE: the pass over the contact nodes at each residual (tool distance, sets, rows, "
        "masses), as contact.friction.residual (compiled, freefem or check)")
    friction_trace: bool = Field(False, description="FE: write every contact node's sets, gap, pressure, "
                                 "traction and slip at every Newton iteration to fem/friction-trace.csv, as "
                                 "contact.friction.trace (failed increments included)")
    properties_T0: float = Field(273.15, gt=0, description="temperature at which thermal.k and thermal.c hold [K]")
    k_slope: float = Field(0.0, description="dk/dT of the work material [W/m/K^2]")
    c_slope: float = Field(0.0, description="dc/dT of the work material [J/kg/K^2]")
    cut_length: Optional[float] = Field(None, gt=0, description="FE: length of cut, the tool's travel over the "
                                        "load factor 0 -> 1 [m]; default 2 uncut_thickness")
    remesh_every: int = Field(4, ge=0, le=1000, description="FE: remesh the deformed workpiece after every this "
                              "many increments (0: only when the element quality falls below 0.1) [1]")
    edge_size: Optional[float] = Field(None, gt=0, description="FE: element size of the remeshes at the cutting "
                                       "edge [m], graded to geometry.fine * geometry.h around the primary shear "
                                       "zone and the rake contact and to twice that elsewhere "
                                       "(wendel.cutting.fe.size_zones); default: uniform geometry.fine * geometry.h")
    frictional_heat: Optional[bool] = Field(None, description="FE: the rake face's frictional work heats the chip "
                                            "(heat_to_chip of it; the rest goes to the rigid tool, which is not "
                                            "meshed, and leaves the model); needs a heat equation (thermal.coupling "
                                            "monolithic or staggered); default: on with a heat equation, off when "
                                            "adiabatic")
    fe_properties_T: Optional[float] = Field(None, gt=0, description="FE: temperature at which the heat equation's "
                                             "k and c (and rho c of the adiabatic heating) are taken from thermal.k, "
                                             "thermal.c and k_slope, c_slope (the FE's k and c are constant) [K]; "
                                             "default: thermal.k and thermal.c as written (at properties_T0)")
    volumetric: Literal["cell", "fbar"] = Field("cell", description="FE: the updated-Lagrangian volume change, "
                                                "per cell (P1, locks in the isochoric plastic flow) or F-bar "
                                                "(kinematics.volumetric)")
    smooth_features: Optional[float] = Field(None, ge=0, lt=0.5, description="FE: the remeshes drop old boundary "
                                             "nodes of features below the new mesh's size, as remesh.smooth_features "
                                             "[1]; default 0.25 with volumetric = fbar (its chip front folds into "
                                             "notches a few um deep: fresh meshes of quality 0.09, measured), 0 "
                                             "(none) with cell")
    relax_tol: float = Field(1e-2, gt=0, lt=1, description="FE: a stage of the re-equilibration after a remesh "
                             "but the last hands on to the next at this relative residual, as remesh.relax_tol [1] "
                             "(numerics.newton_tol or less: each stage converged, as before session 24)")
    first_step: Optional[float] = Field(None, gt=0, le=1, description="FE: the first forward step after a remesh as "
                                        "a share of the step, doubled up to it, as remesh.first_step [1]; default "
                                        "0.25 with volumetric = fbar (it converged at 1/16-1/2 of the step after "
                                        "failed tries, measured), 1 (the whole step) with cell")
    snap_to_tool: bool = Field(False, description="FE: the remeshes move new boundary nodes that fall inside the "
                               "tool (on old edges of the machined surface that cut its rounded edge: 1.3-3.4 um "
                               "deep on the F-bar steel cut, measured) onto its surface, as remesh.snap_to_tool")
    trim_chip: Optional[float] = Field(None, gt=0, description="FE: the remeshes cut off the chip's material farther "
                                       "than this many uncut thicknesses from the tool's tip and above the uncut "
                                       "layer (remesh.trim), so that a chip that curls back does not come down onto "
                                       "the workpiece (the model has no self-contact) [1]; default: the whole chip")
    steady_tol: float = Field(0.02, gt=0, le=1, description="FE: the steady state is where F_c, F_t and the chip "
                              "thickness (their remesh-cycle means) stay within this relative spread over "
                              "steady_length of travel [1] (wendel.cutting.fe_steady)")
    steady_length: Optional[float] = Field(None, gt=0, description="FE: the travel over which the steady state is "
                                           "judged [m]; default: one uncut_thickness")
    steady_measure: Literal["cycles", "filtered"] = Field("cycles", description="FE: what stop_when_steady asks of "
                                                          "the cut: the remesh-cycle means within steady_tol over "
                                                          "steady_length (cycles), or the running means over "
                                                          "steady_length within it over twice that (filtered: a "
                                                          "dynamometer's view, blind to the remesh-to-remesh scatter)")
    stop_when_steady: bool = Field(False, description="FE: end the cut at the end of the remesh cycle where the "
                                   "steady state is first found (cut_length is then the most the tool travels); "
                                   "cutting.json's stopped_at_steady says where")
    oxley: OxleyConstants = OxleyConstants()

    @model_validator(mode="after")
    def _edge(self):
        if self.edge_radius > 0.5 * self.uncut_thickness:
            raise ValueError(f"edge_radius ({self.edge_radius:g} m) above half the uncut_thickness "
                             f"({self.uncut_thickness:g} m): the cut is ploughing, outside this model")
        if self.edge_size is not None and self.edge_size > self.uncut_thickness:
            raise ValueError(f"edge_size ({self.edge_size:g} m) above the uncut_thickness ({self.uncut_thickness:g} m): "
                             "the edge would be coarser than the chip")
        if self.rake + self.clearance >= 80:
            raise ValueError(f"rake + clearance = {self.rake + self.clearance:g} deg leaves a wedge under 10 deg")
        return self


def options(block: Cutting, scene, files) -> list[str]:
    """No FreeFEM options: ``wendel run`` solves the mechanics scene :func:`wendel.cutting.fe.fe_scene`
    derives from the cutting scene (this block is not in it)."""
    raise ValueError("a [cutting] scene is run through wendel.cutting.fe (wendel run SCENE.toml), not as a block")


FE_NUMERICS = {"direct", "newton_tol", "timeout"}      # the [numerics] keys wendel.cutting.fe.fe_scene passes on


def check(block: Cutting, scene) -> None:
    """Rules joining [cutting] with [plasticity], [thermal] and [geometry], applied when the scene is read."""
    plast = getattr(scene, "plasticity", None)
    if plast is None or plast.law != "johnson-cook":
        raise ValueError("cutting needs a [plasticity] table with law = \"johnson-cook\" (the work material)")
    th = getattr(scene, "thermal", None)
    if th is None:
        raise ValueError("cutting needs a [thermal] table (density, conductivity, heat capacity of the work material)")
    if block.frictional_heat and th.coupling == "adiabatic":
        raise ValueError("cutting.frictional_heat = true needs a heat equation to receive it: thermal.coupling = "
                         "\"staggered\" or \"monolithic\" (\"adiabatic\" heats the quadrature points by plastic work only)")
    if block.fe_properties_T is not None:
        k = th.k + block.k_slope * (block.fe_properties_T - block.properties_T0)
        c = th.c + block.c_slope * (block.fe_properties_T - block.properties_T0)
        if not (k > 0 and c > 0):
            raise ValueError(f"cutting.fe_properties_T ({block.fe_properties_T:g} K) gives k = {k:g} W/m/K, "
                             f"c = {c:g} J/kg/K from thermal.k, thermal.c and the slopes: both must be > 0")
    ignored = sorted(scene.numerics.model_fields_set - FE_NUMERICS)
    if ignored:         # the FE cut's own numerics (wendel.cutting.fe.fe_scene): these would be read and not used
        raise ValueError(f"numerics.{ignored[0]}: a cutting scene's FE cut takes only numerics.direct, "
                         f"newton_tol and timeout (it solves with the direct solver on one rank, as fe_scene sets)")
    g = scene.geometry
    if g.builder == "orthogonal-cutting":
        uncut = (g.model_extra or {}).get("uncut")
        if not isinstance(uncut, (int, float)) or isinstance(uncut, bool):
            return      # absent, or not a number: the builder keywords' own validation names it
        if abs(float(uncut) - block.uncut_thickness) > 1e-9 * block.uncut_thickness:
            raise ValueError(f"geometry.uncut ({float(uncut):g} m) and cutting.uncut_thickness "
                             f"({block.uncut_thickness:g} m) must be equal")


register(Block(name="cutting", model=Cutting, options=options, check=check))
