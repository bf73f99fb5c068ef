"""Run the FE cut of a cutting scene and report it per increment: forces, chip, contact, frames.

``wendel run workflows/cutting-*.toml`` comes here (:func:`run_cut`): the mechanics scene of
:func:`wendel.cutting.fe.fe_scene` is solved like any other (its run folder, VTU series, remeshes), then
:func:`report` reads each increment's VTU (updated Lagrangian: the points are the current positions, mm)
and record and writes ``cutting.csv`` and ``cutting.json`` in the run folder, and ``frames/inc-NNNN.png``:

- ``Fc_N``, ``Ft_N``: cutting and thrust force on the tool for the width b [N] (:func:`wendel.cutting.fe.forces`);
- ``chip_rise_m``: how far the highest material point stands above the top of the uncut layer [m] (0 before
  any chip forms; the chip test's measure);
- ``contact_length_m``: the largest distance from the tool tip, along the rake face, of a node in contact
  (``friction_state`` > 0) [m];
- ``chip_thickness_m``: :func:`wendel.cutting.chip.chip_thickness` of the free boundary nodes above 1.1 h
  and between 1 and 2 h up the rake face from the tip, of the chip's first layer on the rake face's normal (a
  chip curled back over that band is not counted twice) (NaN while the chip is shorter than that);
- ``shear_angle_deg``: from the chip ratio (:func:`wendel.cutting.chip.shear_angle`; NaN without a chip thickness);
- ``max_T_primary_K``, ``max_T_secondary_K``: the largest temperature of the primary and the secondary (tool-chip)
  shear zone (:mod:`wendel.cutting.fe_zones`: within 0.25 h of the shear plane and more than 0.2 h from the tool;
  within 0.2 h of the rake face and the edge, above the tip);
- ``tool_travel_m``, ``max_plastic_strain``, ``max_temperature_K`` (NaN without heat), ``elements``;
- ``heat_plastic_J``, ``heat_friction_chip_J``, ``heat_friction_tool_J``, ``heat_stored_J``: the run's heat ledger
  for the width b (Taylor-Quinney heat, the frictional heat into the chip and into the tool, the heat stored in
  the workpiece; NaN where the record has none).

``cutting.json`` adds the Oxley prediction of the same scene (``wendel oxley``), the last increment's
values beside it and the steady state (:mod:`wendel.cutting.fe_steady`, within ``cutting.steady_tol`` over
``cutting.steady_length`` of travel, one h by default; ``stopped_at_steady`` where the cut ended there,
:mod:`.fe_stop`);
``chip.gif`` animates every second frame. ``summary.json["outputs"]`` gets the means over the last
``cutting.steady_length`` of travel (``steady_Fc_N``, ``steady_Ft_N``, ``steady_chip_m``, their cycle-mean spreads and
drifts: :func:`wendel.cutting.fe_steady.window`; with ``cutting.stop_when_steady`` also ``stopped_at_steady_m``), the
numbers a campaign (``wendel sweep``) tabulates and plots.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from . import chip
from .fe import MM, fe_scene, forces, tool_at_start
from .fe_stop import FILE as STOP_FILE, length, rule

SCENE_JSON = "cutting-scene.json"      # the cutting scene as run (report_resumed)
COLUMNS = ["increment", "load_factor", "tool_travel_m", "Fc_N", "Ft_N", "chip_rise_m", "contact_length_m",
           "chip_thickness_m", "shear_angle_deg", "max_plastic_strain", "max_temperature_K", "max_T_primary_K",
           "max_T_secondary_K", "heat_plastic_J", "heat_friction_chip_J", "heat_friction_tool_J", "heat_stored_J",
           "elements"]
LEDGER = {"heat_plastic_J": "heat_plastic", "heat_friction_chip_J": "friction_heat_body",
          "heat_friction_tool_J": "friction_heat_tool", "heat_stored_J": "thermal_energy_change"}
"""cutting.csv's heat columns and the record's keys (mJ per mm of width in the FE scene's units)."""


def run_cut(scene, scene_path: Path, out: Path, smoke: bool, progress=print, frames: bool = True) -> Path:
    """Solve the FE cut of the validated cutting ``scene`` into ``out``; report it (see the module)."""
    from ..loop.quasistatic import run_scene
    from ..scene import load
    travel = scene.loading.steps / load(scene_path).loading.steps if smoke else 1.0
    try:
        root = Path(run_scene(fe_scene(scene, travel), scene_path, out, smoke, progress,
                              record={SCENE_JSON: as_set(scene)}, until=rule(Path(out).resolve(), scene, progress)))
    except Exception:
        root = Path(out).resolve()
        if (root / "history.csv").is_file():       # a cut that stops: its accepted increments are reported
            report(root, scene, frames=frames, travel=travel)
        raise
    rows = report(root, scene, frames=frames, travel=travel)
    if rows:
        r = rows[-1]
        progress(f"  cut {r['tool_travel_m'] * 1e3:.4g} mm: F_c = {r['Fc_N']:.4g} N, F_t = {r['Ft_N']:.4g} N, "
                 f"chip rise {r['chip_rise_m'] * 1e3:.4g} mm, contact length {r['contact_length_m'] * 1e3:.4g} mm "
                 f"(cutting.csv, frames/)")
    return root


def cutting_scene(root: Path):
    """The cutting scene of the run folder ``root`` as run (a bench or a script may have changed the file's), else
    the file's; None for a run folder of any other scene."""
    from ..scene import SceneError, load
    from ..scene.schema import Scene
    try:
        scene = Scene.model_validate_json((root / SCENE_JSON).read_text()) if (root / SCENE_JSON).is_file() \
            else load(root / "scene.toml")
    except (SceneError, OSError, ValueError):
        return None
    return scene if getattr(scene, "cutting", None) is not None else None


def resumed_rule(root: Path, progress=print):
    """The stop rule (:mod:`.fe_stop`) of a cut resumed in ``root``, None for other run folders."""
    scene = cutting_scene(Path(root))
    return rule(Path(root), scene, progress) if scene is not None else None


def report_resumed(root: Path, progress=print) -> Path:
    """The cutting report of a cut that ``wendel run --resume`` finished (a sweep resumes interrupted runs so): the run
    folder's scene.toml is the cutting scene; the share of the cut (a smoke cut is its first increments) is read
    from the FE scene that was solved. Nothing for a run folder of any other scene. Returns ``root``."""
    root = Path(root)
    scene = cutting_scene(root)
    if scene is None:
        return root
    solved = json.loads((root / "scene.resolved.json").read_text())["contact"]["path"]["x"][-1]
    travel = solved / fe_scene(scene).contact.path.x[-1]
    rows = report(root, scene, frames=True, travel=travel)
    if rows:
        progress(f"  cut {rows[-1]['tool_travel_m'] * 1e3:.4g} mm: F_c = {rows[-1]['Fc_N']:.4g} N (cutting.csv, frames/)")
    return root


def as_set(model) -> dict:
    """The fields of a pydantic ``model`` that were read or assigned, nested (a sub-table changed in place
    counts, though its own field was never assigned): the cutting scene as run, valid again as a scene."""
    from pydantic import BaseModel
    out = model.model_dump(mode="json", exclude_unset=True)
    for name in type(model).model_fields:
        value = getattr(model, name)
        if isinstance(value, BaseModel):
            sub = as_set(value)
            if sub or name in out:
                out[name] = sub
    return out


def _boundary_nodes(cells: np.ndarray) -> np.ndarray:
    from ..remesh.mesher import boundary_facets
    return np.unique(boundary_facets(cells))


def measure(points: np.ndarray, cells: np.ndarray, state: np.ndarray, tip: np.ndarray, rake: float,
            h: float) -> dict:
    """Chip rise, contact length and chip thickness [mm] of one increment (positions in mm)."""
    along = np.array([math.sin(rake), math.cos(rake)])
    rise = max(float(points[:, 1].max()) - h, 0.0)
    active = state > 0.5
    length = float(((points[active] - tip) @ along).max()) if active.any() else 0.0
    free = _boundary_nodes(cells)
    free = free[~active[free] & (points[free, 1] > 1.1 * h)]      # the chip's back surface: risen above the layer
    try:
        thickness, _ = chip.chip_thickness(points[free], tip, rake, (h, 2 * h), mesh=(points, cells))
    except ValueError:
        thickness = float("nan")
    return {"chip_rise": rise, "contact_length": max(length, 0.0), "chip_thickness": thickness}


def tool_start(scene, fe=None) -> dict:
    """The tool of the cutting ``scene`` at load factor 0 (:func:`wendel.cutting.fe.tool_at_start` in front of the
    step of its FE scene ``fe``, by default ``fe_scene(scene)``)."""
    extra = (fe or fe_scene(scene)).geometry.model_extra
    return tool_at_start(scene.cutting, extra["length"] - extra["pre_cut"])


def measured(rec: dict, m, tip0: np.ndarray, rake: float, h: float, width: float) -> tuple:
    """One increment's tool shift [mm], :func:`measure` and forces F_c, F_t [N] from its history record ``rec`` and
    its VTU ``m`` (meshio; the tool's tip at load factor 0 ``tip0``, the uncut thickness ``h`` in mm)."""
    shift = np.array([float(rec.get("tool_x") or 0.0), float(rec.get("tool_y") or 0.0)])
    got = measure(m.points[:, :2], m.cells_dict["triangle"], np.asarray(m.point_data["friction_state"]).ravel(),
                  tip0 + shift, rake, h)
    return shift, got, *forces(rec, width)


def report(root: Path, scene, frames: bool = True, travel: float = 1.0) -> list[dict]:
    """Per-increment cutting outputs of the run folder ``root`` (see the module); returns the rows."""
    import meshio
    c = scene.cutting
    h, rake = c.uncut_thickness * MM, math.radians(c.rake)
    fe = fe_scene(scene, travel)
    start = tool_start(scene, fe)
    tip0 = np.array(start["tip"])
    history = list(csv.DictReader((root / "history.csv").open()))
    from .fe_frames import rounded_outline
    from .fe_zones import PHI_DEFAULT, zone_temperatures
    outline0 = rounded_outline(start["vertices"], start["radii"], per_arc=16)
    try:
        from .scene import predict
        phi_oxley = predict(scene).phi
    except (ValueError, ArithmeticError):
        phi_oxley = math.radians(PHI_DEFAULT)
    rows = []
    for rec in history:
        inc = int(rec["increment"])
        vtu_path = root / "vtu" / f"inc-{inc:04d}.vtu"
        if not vtu_path.is_file():
            continue
        m = meshio.read(vtu_path)
        points = m.points[:, :2]
        cells = m.cells_dict["triangle"]
        shift, got, fc, ft = measured(rec, m, tip0, rake, h, c.width)
        t2 = got["chip_thickness"]
        phi = chip.shear_angle(h, t2, rake) if t2 == t2 and t2 > 0 else float("nan")
        temps = zone_temperatures(m, outline0 + shift, tip0 + shift, rake, h, phi if phi == phi else phi_oxley)
        ledger = {k: _num(rec.get(v)) * c.width for k, v in LEDGER.items()}     # mJ/mm * m = J
        if fe.thermal is None or fe.thermal.coupling == "adiabatic":             # no heat equation takes it
            ledger["heat_friction_chip_J"] = ledger["heat_friction_tool_J"] = float("nan")
        rows.append({"increment": inc, "load_factor": float(rec["load_factor"]), "tool_travel_m": -shift[0] / MM,
                     "Fc_N": fc, "Ft_N": ft, "chip_rise_m": got["chip_rise"] / MM,
                     "contact_length_m": got["contact_length"] / MM, "chip_thickness_m": got["chip_thickness"] / MM,
                     "shear_angle_deg": math.degrees(phi),
                     "max_plastic_strain": float(rec.get("max_plastic_strain") or 0.0),
                     "max_temperature_K": float(rec.get("max_temperature") or "nan"), **temps, **ledger,
                     "elements": int(float(rec["elements"]))})
        if frames:
            from .fe_frames import frame
            frame(root / "frames" / f"inc-{inc:04d}.png", points, cells, m.cell_data.get("p"), start, shift,
                  f"{scene.description[:70]}\nincrement {inc}: travel {-shift[0] * 1e3:.1f} um, "
                  f"F_c {fc:.0f} N, F_t {ft:.0f} N", h)
    with (root / "cutting.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    coupling = fe.thermal.coupling if fe.thermal is not None else None
    summary = {"last": rows[-1] if rows else None, "width_m": c.width, "adiabatic": coupling == "adiabatic",
               "thermal_coupling": coupling}
    if rows:
        from .fe_steady import cycle_means, gif, steady
        summary["steady"] = steady(rows, length(scene), c.steady_tol)
        summary["zone_temperatures"] = {"cycle_means": cycle_means(rows, ("max_T_primary_K", "max_T_secondary_K")),
                                        "zones": "primary: within 0.25 h of the shear plane, more than 0.2 h "
                                                 "from the tool; secondary: within 0.2 h of the rake face and the "
                                                 "edge, above the tip (wendel.cutting.fe_zones)"}
        if frames:
            gif(root / "frames", root / "chip.gif", every=2)
    if (root / STOP_FILE).is_file():       # the cut ended at its steady state (cutting.stop_when_steady)
        summary["stopped_at_steady"] = json.loads((root / STOP_FILE).read_text())
    try:
        from .scene import predict, row
        summary["oxley"] = row(predict(scene))
    except (ValueError, ArithmeticError) as exc:         # outside the model's domain: say so, keep the FE
        summary["oxley"] = {"refused": str(exc)}
    (root / "cutting.json").write_text(json.dumps(summary, indent=1, default=float))
    if rows and (root / "summary.json").is_file():        # the steady figures for a campaign (wendel sweep's table)
        from .fe_steady import window
        s = json.loads((root / "summary.json").read_text())
        s["outputs"] = {**(s.get("outputs") or {}), **window(rows, length(scene))}
        if c.stop_when_steady:        # where the cut ended at its steady state, NaN where it never got there
            s["outputs"]["stopped_at_steady_m"] = summary.get("stopped_at_steady", {}).get("tool_travel_m", math.nan)
        (root / "summary.json").write_text(json.dumps(s, indent=1, default=float))
    return rows


def _num(v) -> float:
    """A record's value as a float, NaN where it is missing or empty."""
    try:
        return float(v)
    except (TypeError, ValueError):
        return float("nan")
