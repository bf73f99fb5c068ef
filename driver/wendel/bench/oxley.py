"""Benchmarks of the orthogonal-cutting analytics: ``oxley``, ``oxley-domain`` and ``oxley-kienzle``.

``oxley``: the extended Oxley model on the published AISI 1045 case (Lalwani et al. 2009) with each
choice of where the secondary zone's k and c are taken, against the two published implementations'
range, with the wall time of a solve; and the model at the four conditions of the NIST AISI 1045
tests (Ivester et al. 2000: V = 200, 300 m/min; h = 0.15, 0.30 mm; rake -7 deg; b = 1.6 mm); and the model
against the eight measured AISI 1045 cuts of :data:`wendel.cutting.experiments.AISI1045` (V = 200, 400 m/min,
h = 0.15, 0.30 mm, rake -7, +5 deg: their measured F_c and F_t, the differences, and the transcribing file's own
Oxley implementation at each).

``oxley-kienzle``: Oxley over speed x uncut chip thickness x rake for the AISI 1045 and Ti-6Al-4V
scenes, Kienzle's k_c1.1 and m_c fitted per (speed, rake) and per rake, beside catalogue values.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

from . import WORKFLOWS, register

# Lalwani et al. (2009) and Pantale et al. (2022), as quoted in issue 17: (low, high)
PUBLISHED_AISI1045 = {"Fc": (571.0, 576.0), "Ft": (353.0, 364.0), "chip_mm": (0.42, 0.43), "T_int_C": (942.0, 948.0)}


def distance_to_range(value: float, lo: float, hi: float) -> float:
    """Relative distance of ``value`` to [lo, hi] (0 inside)."""
    if value < lo:
        return (value - lo) / lo
    if value > hi:
        return (value - hi) / hi
    return 0.0


@register("oxley")
def oxley_bench(quick: bool, workdir: Path) -> list[dict]:
    from ..cutting import oxley
    from ..cutting.scene import inputs
    from ..scene import load

    scene = load(WORKFLOWS / "cutting-aisi1045.toml")
    mat, th, cut, opt = inputs(scene)
    rows = []
    for prop in oxley.PROPERTY_TEMPERATURES:
        r = oxley.predict(mat, th, cut, dataclasses.replace(opt, properties=prop))
        got = {"Fc": r.Fc, "Ft": r.Ft, "chip_mm": r.chip_thickness * 1e3, "T_int_C": r.T_int - 273.15}
        row = {"case": "Lalwani 2009 AISI 1045", "properties": prop, "V_m_per_min": 200, "h_mm": 0.15}
        row.update({k: v for k, v in got.items()})
        row.update({f"{k}_off_range": distance_to_range(v, *PUBLISHED_AISI1045[k]) for k, v in got.items()})
        row.update({"phi_deg": math.degrees(r.phi), "C0": r.C0, "delta": r.delta, "evaluations": r.evaluations,
                    "ms": r.seconds * 1e3})
        rows.append(row)
    # how flat F_c is in delta (the minimum-work condition) and how much T_int moves with it
    best = rows[[r["properties"] for r in rows].index(opt.properties)]
    model = oxley._Model(mat, th, cut, opt)
    for f in (0.5, 0.75, 1.25, 1.5):
        s = model.solve_delta(f * best["delta"])
        rows.append({"case": f"delta = {f:g} x the optimum", "properties": opt.properties, "V_m_per_min": 200,
                     "h_mm": 0.15, "Fc": s["Fc"], "Ft": s["Ft"], "chip_mm": s["t2"] * 1e3,
                     "T_int_C": s["T_int"] - 273.15, "phi_deg": math.degrees(s["phi"]), "C0": s["C0"],
                     "delta": s["delta"]})
    for v, h in ((200, 0.15), (200, 0.30), (300, 0.15), (300, 0.30)):
        mat, th, cut, opt = inputs(scene, speed=v / 60, uncut=h * 1e-3)
        r = oxley.predict(mat, th, cut, opt)
        rows.append({"case": "NIST AISI 1045 conditions", "properties": opt.properties, "V_m_per_min": v,
                     "h_mm": h, "Fc": r.Fc, "Ft": r.Ft, "chip_mm": r.chip_thickness * 1e3,
                     "T_int_C": r.T_int - 273.15, "phi_deg": math.degrees(r.phi), "C0": r.C0, "delta": r.delta,
                     "evaluations": r.evaluations, "ms": r.seconds * 1e3})
    rows += measured_aisi1045(scene)
    return rows


def measured_aisi1045(scene) -> list[dict]:
    """Oxley at each measured AISI 1045 cut of :data:`wendel.cutting.experiments.AISI1045` (the scene's material,
    width and options, the cut's V, h and rake) against its measured F_c and F_t, with the differences."""
    from ..cutting import oxley
    from ..cutting.experiments import AISI1045, AISI1045_MODEL, AISI1045_SOURCE
    from ..cutting.scene import inputs
    rows = []
    for e, (fc, ft, chip) in zip(AISI1045, AISI1045_MODEL):
        r = oxley.predict(*inputs(scene, speed=e.V / 60, uncut=e.h * 1e-3, rake=e.rake))
        rows.append({"case": "measured AISI 1045 cut", "V_m_per_min": e.V, "h_mm": e.h, "rake_deg": e.rake,
                     "Fc": r.Fc, "Ft": r.Ft, "chip_mm": r.chip_thickness * 1e3, "T_int_C": r.T_int - 273.15,
                     "Fc_measured": e.Fc, "Ft_measured": e.Ft, "dFc_measured": r.Fc / e.Fc - 1,
                     "dFt_measured": r.Ft / e.Ft - 1, "Fc_other_oxley": fc, "Ft_other_oxley": ft,
                     "chip_other_oxley_mm": chip, "source": AISI1045_SOURCE})
    return rows


@register("oxley-domain")
def oxley_domain(quick: bool, workdir: Path) -> list[dict]:
    """Where the model has a solution: V 20-1000 m/min x h 0.01-1 mm x rake -20..30 deg for both scenes;
    every point either solves (its residuals checked) or is refused with OxleyError."""
    import itertools

    from ..cutting import oxley
    from ..cutting.scene import inputs
    from ..scene import load

    speeds = [20, 100, 1000] if quick else [20, 50, 100, 300, 600, 1000]
    uncuts = [0.01, 0.1, 1.0] if quick else [0.01, 0.02, 0.05, 0.1, 0.3, 0.6, 1.0]
    rakes = [-20, 0, 30] if quick else [-20, -10, 0, 10, 20, 30]
    rows = []
    for scene_file in ("cutting-aisi1045.toml", "cutting-ti6al4v.toml"):
        scene = load(WORKFLOWS / scene_file)
        for v, h, rake in itertools.product(speeds, uncuts, rakes):
            row = {"scene": scene_file, "V_m_per_min": v, "h_mm": h, "rake_deg": rake}
            try:
                r = oxley.predict(*inputs(scene, speed=v / 60, uncut=h * 1e-3, rake=rake))
            except oxley.OxleyError:
                rows.append({**row, "status": "refused"})
                continue
            s = oxley._Model(*inputs(scene, speed=v / 60, uncut=h * 1e-3, rake=rake)).state(r.phi, r.C0, r.delta)
            rows.append({**row, "status": "solved", "Fc": r.Fc, "Ft": r.Ft, "max_residual":
                         max(abs(s["res_phi"]), abs(s["res_C0"])), "ms": r.seconds * 1e3})
    return rows


@register("oxley-kienzle")
def kienzle_bench(quick: bool, workdir: Path) -> list[dict]:
    from ..cutting import campaign
    from ..scene import load

    plans = {
        "aisi1045": ("cutting-aisi1045.toml", [100, 200, 300, 400]),
        "ti6al4v": ("cutting-ti6al4v.toml", [30, 60, 90, 120]),
    }
    uncuts = [0.05, 0.1, 0.2, 0.3] if quick else [0.05, 0.075, 0.1, 0.15, 0.2, 0.25, 0.3]
    rakes = [-7, 0, 7]
    out = []
    for material, (scene_file, speeds) in plans.items():
        scene = load(WORKFLOWS / scene_file)
        rows = campaign.run(scene, speeds[:2] if quick else speeds, uncuts, rakes)
        failed = [r for r in rows if r["status"] != "ok"]
        for f in campaign.fits(rows):
            out.append({"material": material, "source": "Oxley fit", **f, "points_without_solution": len(failed)})
        for c in campaign.CATALOGUE[material]:
            out.append({"material": material, "source": c["source"], "kc11_N_per_mm2": c["kc11_N_per_mm2"],
                        "mc": c["mc"]})
        # F_c at the scene's speed and width, rake 0 (the catalogues' neutral tool), against each catalogue law
        v = scene.cutting.speed * 60
        for h in (0.1, 0.2):
            r = campaign.run(scene, [v], [h], [0.0])[0]
            for c in campaign.CATALOGUE[material]:
                fc_cat = r["b"] * 1e3 * c["kc11_N_per_mm2"] * h ** (1 - c["mc"])
                out.append({"material": material, "source": f"F_c at V = {v:.0f} m/min, h = {h} mm, rake 0: "
                            f"Oxley / {c['source'].split(':')[0]}", "speed_m_per_min": v, "rake_deg": 0.0,
                            "h_min_mm": h, "h_max_mm": h, "Fc_oxley_N": r["Fc"], "Fc_catalogue_N": fc_cat,
                            "Fc_difference": r["Fc"] / fc_cat - 1.0})
    return out
