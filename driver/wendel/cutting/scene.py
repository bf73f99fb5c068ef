"""From a cutting scene to the extended Oxley model, and the prediction written as JSON and CSV.

``wendel oxley SCENE.toml`` calls :func:`analytic`: the model's inputs come from the scene's
``[cutting]``, ``[plasticity]`` (Johnson-Cook) and ``[thermal]`` tables, so the FE run and the analytic
companion read the same numbers.

>>> from pathlib import Path
>>> from wendel.scene import load
>>> s = load(Path(__file__).parents[3] / "workflows" / "cutting-aisi1045.toml")
>>> mat, th, cut, opt = inputs(s)
>>> round(mat.A / 1e6, 1), round(th.k(298.15), 3), round(cut.speed * 60)
(553.1, 51.907, 200)
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
from pathlib import Path

from . import oxley
from .tool import from_scene

# The quantities written, with their units (JSON keys and CSV columns).
COLUMNS = [
    ("Fc", "N", 1.0), ("Ft", "N", 1.0), ("chip_thickness", "mm", 1e3), ("chip_ratio", "1", 1.0),
    ("phi", "deg", math.degrees(1.0)), ("friction_angle", "deg", math.degrees(1.0)),
    ("friction_coefficient", "1", 1.0), ("phi_merchant", "deg", math.degrees(1.0)),
    ("phi_lee_shaffer", "deg", math.degrees(1.0)), ("contact_length", "mm", 1e3), ("C0", "1", 1.0),
    ("delta", "1", 1.0), ("T_AB", "C", None), ("T_int", "C", None), ("T_chip", "C", None),
    ("k_AB", "MPa", 1e-6), ("k_int", "MPa", 1e-6), ("sigma_N", "MPa", 1e-6), ("strain_AB", "1", 1.0),
    ("rate_AB", "1/s", 1.0), ("strain_int", "1", 1.0), ("rate_int", "1/s", 1.0), ("beta", "1", 1.0),
    ("inertia", "1", 1.0), ("kinetic", "1", 1.0), ("seconds", "s", 1.0),
]


def inputs(scene, speed: float | None = None, uncut: float | None = None,
           rake: float | None = None) -> tuple[oxley.JohnsonCook, oxley.ThermalProperties, oxley.Cut, oxley.Options]:
    """The model's inputs from a validated scene; ``speed`` [m/s], ``uncut`` [m] and ``rake`` [deg]
    override the scene's (campaigns)."""
    c, p, t = scene.cutting, scene.plasticity, scene.thermal
    if c is None:
        raise ValueError("the scene has no [cutting] table")
    mat = oxley.JohnsonCook(A=p.jc_A, B=p.jc_B, n=p.jc_n, C=p.jc_C, m=p.jc_m, T_melt=p.jc_T_melt,
                            T_room=p.jc_T_room, rate0=p.jc_rate0)
    th = oxley.ThermalProperties(rho=t.rho, k0=t.k, c0=t.c, T0=c.properties_T0, k_slope=c.k_slope,
                                 c_slope=c.c_slope)
    cut = oxley.Cut(speed=c.speed if speed is None else speed,
                    uncut=c.uncut_thickness if uncut is None else uncut, width=c.width,
                    rake=math.radians(c.rake if rake is None else rake),
                    T_work=t.T_initial if t.T_initial is not None else t.T_ref)
    opt = oxley.Options(eta=c.oxley.eta, psi=c.oxley.psi, properties=c.oxley.properties)
    return mat, th, cut, opt


def predict(scene, **overrides) -> oxley.Result:
    """The Oxley prediction of the scene's cut (see :func:`inputs` for the overrides)."""
    return oxley.predict(*inputs(scene, **overrides))


def row(result: oxley.Result) -> dict:
    """The result in the units of :data:`COLUMNS` (keys ``name_unit``)."""
    d = result.as_dict()
    out = {}
    for name, unit, scale in COLUMNS:
        v = d[name]
        out[f"{name}_{unit.replace('/', 'per')}"] = v - 273.15 if scale is None else v * scale
    return out


def friction_shear_angles(friction: float, rake_deg: float) -> dict:
    """Merchant's and Lee-Shaffer's shear angles [deg] from a friction coefficient (e.g. the FE's)."""
    lam, a = math.atan(friction), math.radians(rake_deg)
    return {"friction_angle_deg": math.degrees(lam), "phi_merchant_deg": math.degrees(oxley.merchant(lam, a)),
            "phi_lee_shaffer_deg": math.degrees(oxley.lee_shaffer(lam, a))}


def analytic(scene_path: str | Path, out: Path | None = None, picture: bool = True) -> tuple[dict, Path]:
    """Run the Oxley model on a scene file; write ``oxley.json`` and ``oxley.csv``, the scene's tool polygon
    (``tool.txt``, ``tool.json``) and with ``picture`` a drawing of the solution (``oxley.png``) into ``out``
    (default ``results/<scene>/oxley``); return the record and the folder."""
    from ..scene import load

    scene_path = Path(scene_path)
    scene = load(scene_path)
    result = predict(scene)
    c = scene.cutting
    record = {
        "scene": str(scene_path), "description": scene.description,
        "inputs": {"speed_m_per_s": c.speed, "uncut_thickness_m": c.uncut_thickness, "width_m": c.width,
                   "rake_deg": c.rake, "oxley": c.oxley.model_dump()},
        "oxley": row(result),
        "from_scene_friction": {"friction": c.friction, **friction_shear_angles(c.friction, c.rake)},
        "evaluations": result.evaluations,
    }
    if out is None:
        out = Path(__file__).resolve().parents[3] / "results" / scene_path.stem / "oxley"
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "oxley.json").write_text(json.dumps(record, indent=1))
    with open(out / "oxley.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(record["oxley"]))
        w.writeheader()
        w.writerow(record["oxley"])
    tool = from_scene(c)           # the FE's tool, tip at the origin: vertices for the polygon tool
    tool.write(out / "tool.txt")
    (out / "tool.json").write_text(tool.to_json())
    if picture:
        from .picture import oxley_picture

        oxley_picture(result, tool, out / "oxley.png", title=f"{scene_path.stem}: extended Oxley model")
    return record, out


def summary_lines(record: dict) -> list[str]:
    """The record as a few lines for the terminal."""
    o, f = record["oxley"], record["from_scene_friction"]
    i = record["inputs"]
    return [
        f"Oxley (extended, Johnson-Cook): V = {i['speed_m_per_s'] * 60:.0f} m/min, h = "
        f"{i['uncut_thickness_m'] * 1e3:g} mm, b = {i['width_m'] * 1e3:g} mm, rake {i['rake_deg']:g} deg",
        f"  F_c = {o['Fc_N']:.1f} N, F_t = {o['Ft_N']:.1f} N, chip thickness {o['chip_thickness_mm']:.4f} mm "
        f"(ratio {o['chip_ratio_1']:.3f})",
        f"  shear angle {o['phi_deg']:.2f} deg, friction angle {o['friction_angle_deg']:.2f} deg "
        f"(mu = {o['friction_coefficient_1']:.3f}), contact length {o['contact_length_mm']:.3f} mm",
        f"  T_AB = {o['T_AB_C']:.0f} C, T_int = {o['T_int_C']:.0f} C, mean chip {o['T_chip_C']:.0f} C; "
        f"C0 = {o['C0_1']:.3f}, delta = {o['delta_1']:.4f}; {o['seconds_s'] * 1e3:.0f} ms",
        f"  inertia: rho V_s^2 / k_AB = {o['inertia_1']:.1e}, chip kinetic energy / cutting work = "
        f"{o['kinetic_1']:.1e} ({'below 1 %: quasi-static steps are enough' if o['inertia_1'] < 0.01 else 'inertia matters'})",
        f"  shear angle from Oxley's friction angle: Merchant {o['phi_merchant_deg']:.1f} deg, Lee-Shaffer "
        f"{o['phi_lee_shaffer_deg']:.1f} deg",
        f"  from the scene's friction mu = {f['friction']:g} (lambda = {f['friction_angle_deg']:.1f} deg): "
        f"Merchant {f['phi_merchant_deg']:.1f} deg, Lee-Shaffer {f['phi_lee_shaffer_deg']:.1f} deg",
    ]
