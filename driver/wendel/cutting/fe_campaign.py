"""Kienzle's k_c1.1 and m_c from an FE cutting campaign (``wendel sweep`` of a cutting scene), beside Oxley's and
the catalogues'.

The sweep's table (``sweep.csv``, :func:`wendel.sweep.collect`) carries each cut's steady figures
(``steady_Fc_N`` ...: the means over the cut's last h of travel, :func:`wendel.cutting.fe_steady.window`); the
speed, rake, uncut chip thickness and width of each cut are read from its scene (``scenes/<key>.toml``), so any
of them may be swept. :func:`points` makes one row per finished cut with the Oxley model's F_c at the same
conditions; :func:`compare` fits F_c = b k_c1.1 h^(1 - m_c) (:func:`wendel.cutting.kienzle.fit_groups`) to the FE
and to the Oxley forces per (speed, rake) and puts the catalogue constants (:data:`wendel.cutting.campaign.CATALOGUE`)
beside them; :func:`plot` draws F_c against h (log-log).
"""

from __future__ import annotations

import math
from pathlib import Path

from . import kienzle
from .campaign import CATALOGUE

GROUP = ("speed_m_per_min", "rake_deg")


def points(root: Path) -> list[dict]:
    """One row per cut of the sweep folder ``root`` that is done and has a finite ``steady_Fc_N``; the rows of the
    other cuts are returned with ``status`` saying why they are left out (never silently)."""
    from ..scene import load
    from ..sweep import collect
    from .scene import inputs
    from . import oxley

    _, table = collect(Path(root))
    out = []
    for r in table:
        scene = load(Path(root) / "scenes" / f"{r['key']}.toml")
        c = scene.cutting
        row = {"key": r["key"], "speed_m_per_min": round(c.speed * 60, 6), "rake_deg": c.rake, "h": c.uncut_thickness,
               "b": c.width, "edge_radius_m": c.edge_radius, "edge_size_m": c.edge_size, "status": r["status"]}
        fc = r.get("steady_Fc_N")
        if r["status"] != "done" or not isinstance(fc, (int, float)) or not math.isfinite(fc) or fc <= 0:
            row["status"] = f"left out: {r['status']}" + (f" ({r.get('message')})" if r.get("message") else "")
            out.append(row)
            continue
        row.update({"status": "ok", "Fc": fc, "Ft": r.get("steady_Ft_N"), "chip_m": r.get("steady_chip_m"),
                    "Fc_spread": r.get("steady_Fc_N_spread"), "Fc_trend": r.get("steady_Fc_N_trend"),
                    "Ft_spread": r.get("steady_Ft_N_spread"), "chip_spread": r.get("steady_chip_m_spread"),
                    "window_from_m": r.get("steady_window_from_m"), "window_to_m": r.get("steady_window_to_m"),
                    "cycles": r.get("steady_cycles"), "increments": r.get("increments"),
                    "wall_time_s": r.get("wall_time"), "run_wall_s": r.get("run_wall")})
        try:
            o = oxley.predict(*inputs(scene))
            row.update({"Fc_oxley": o.Fc, "Ft_oxley": o.Ft, "chip_oxley_m": o.chip_thickness,
                        "Fc_fe_over_oxley": fc / o.Fc - 1.0})
        except oxley.OxleyError as exc:
            row["oxley"] = f"no solution: {exc}"
        out.append(row)
    return out


def compare(rows: list[dict], material: str) -> list[dict]:
    """The fits of the FE and the Oxley forces per (speed, rake), with the catalogue constants of ``material``
    beside each: ``kc11_N_per_mm2``, ``mc``, and for the FE fits their differences to Oxley's and to each
    catalogue's (``kc11`` relative, ``mc`` absolute, F_c at the middle of the h range relative)."""
    ok = [r for r in rows if r["status"] == "ok"]
    fe = kienzle.fit_groups(ok, by=GROUP) if ok else {}
    ox = kienzle.fit_groups([{**r, "Fc": r["Fc_oxley"]} for r in ok if "Fc_oxley" in r], by=GROUP) if ok else {}
    out = []
    for g, f in fe.items():
        b = next(r["b"] for r in ok if tuple(r[k] for k in GROUP) == g)
        h_mid = math.sqrt(f.h_range[0] * f.h_range[1])
        base = dict(zip(GROUP, g))
        fe_row = {**base, "source": "FE fit", **f.as_dict(), "Fc_at_h_mid_N": f.force(h_mid, b), "h_mid_mm": h_mid * 1e3}
        out.append(fe_row)
        refs = []
        if g in ox:
            o = ox[g]
            refs.append(("Oxley fit", o.kc11 / 1e6, o.mc, {**o.as_dict()}))
        for c in CATALOGUE.get(material, []):
            refs.append((c["source"], c["kc11_N_per_mm2"], c["mc"], {"kc11_N_per_mm2": c["kc11_N_per_mm2"], "mc": c["mc"]}))
        for source, kc11, mc, d in refs:
            fc_mid = b * 1e3 * kc11 * (h_mid * 1e3) ** (1 - mc)
            out.append({**base, "source": source, **d, "Fc_at_h_mid_N": fc_mid, "h_mid_mm": h_mid * 1e3,
                        "fe_kc11_difference": f.kc11 / 1e6 / kc11 - 1.0, "fe_mc_difference": f.mc - mc,
                        "fe_Fc_at_h_mid_difference": fe_row["Fc_at_h_mid_N"] / fc_mid - 1.0})
    return out


def plot(path: Path, rows: list[dict], fits: list[dict], title: str) -> Path:
    """F_c against h (log-log) per (speed, rake): the FE points and fit, Oxley's points and fit, the catalogue lines."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    ok = [r for r in rows if r["status"] == "ok"]
    groups = sorted({tuple(r[k] for k in GROUP) for r in ok})
    fig, axes = plt.subplots(1, max(len(groups), 1), figsize=(6.2 * max(len(groups), 1), 4.8), squeeze=False)
    for ax, g in zip(axes[0], groups):
        pts = sorted((r for r in ok if tuple(r[k] for k in GROUP) == g), key=lambda r: r["h"])
        b = pts[0]["b"]
        hs = np.array([r["h"] for r in pts]) * 1e3
        line = np.geomspace(hs.min() / 1.3, hs.max() * 1.3, 50)
        ax.loglog(hs, [r["Fc"] for r in pts], "o", color="C0", label="FE (mean over the last h)")
        ax.loglog(hs, [r.get("Fc_oxley", np.nan) for r in pts], "s", color="C1", mfc="none", label="Oxley")
        styles = {"FE fit": ("C0", "-"), "Oxley fit": ("C1", "--")}
        for n, f in enumerate(x for x in fits if tuple(x[key] for key in GROUP) == g):
            color, ls = styles.get(f["source"], (f"C{n + 1}", ":"))
            label = f["source"] if f["source"] in styles else f["source"].split(":")[0]
            ax.loglog(line, b * 1e3 * f["kc11_N_per_mm2"] * line ** (1 - f["mc"]), ls, color=color, lw=1.2,
                      label=f"{label}: k_c1.1 {f['kc11_N_per_mm2']:.0f} N/mm^2, m_c {f['mc']:.2f}")
        from matplotlib.ticker import ScalarFormatter
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_formatter(ScalarFormatter())
            axis.set_minor_formatter(ScalarFormatter())
        ax.tick_params(which="minor", labelsize=6)
        ax.set_xlabel("uncut chip thickness h [mm]")
        ax.set_ylabel(f"F_c [N] (b = {b * 1e3:g} mm)")
        ax.set_title(f"{g[0]:g} m/min, rake {g[1]:g} deg", fontsize=10)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=6.5)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
