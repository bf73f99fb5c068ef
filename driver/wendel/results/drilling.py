"""What a drilling run leaves besides the VTU series: the bore profile, CSV tables and the pictures."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from ..meshes import LABELS
from . import vtu as output


def bore_profile(mesh: dict, inc_dir: Path, axis, height: float, bins: int, dim: int = 3) -> dict | None:
    """Along the depth: mean of 2 u_r at the bore-wall nodes (m) and of the hoop and axial stress (Pa) of
    the cells touching the wall, in ``bins`` depth bins (NaN where a bin has no node). ``dim = 2``: the
    (r, z) section (x = r, y = z; u_r = u_x, hoop stress = stress_zz, axial = stress_yy)."""
    p, f, tags, cells = mesh["points"], mesh["facets"], mesh["tags"], mesh["cells"]
    wall = np.unique(f[tags == LABELS["bore_wall"]])
    if len(wall) == 0:
        return None
    name = "u_total.node.txt" if (inc_dir / "u_total.node.txt").is_file() else "u.node.txt"
    u = output.read_array(inc_dir / name).reshape(-1, dim)
    if dim == 2:
        ur, s = u[wall, 0], height - p[wall, 1]
    else:
        x, y = p[wall, 0] - axis[0], p[wall, 1] - axis[1]
        r = np.hypot(x, y)
        ur = (u[wall, 0] * x + u[wall, 1] * y) / r
        s = height - p[wall, 2]
    edges = np.linspace(s.min(), s.max(), bins + 1)
    mid = 0.5 * (edges[1:] + edges[:-1])
    idx = np.clip(np.searchsorted(edges, s, side="right") - 1, 0, bins - 1)
    d_err = [float(np.mean(2 * ur[idx == i])) if np.any(idx == i) else float("nan") for i in range(bins)]
    hoop = axial = [float("nan")] * bins
    if (inc_dir / "stress_xx.cell.txt").is_file() and dim == 2:
        on_wall = np.isin(cells, wall).sum(axis=1) >= 2          # triangles with an edge on the wall
        cs = height - p[cells[on_wall]].mean(axis=1)[:, 1]
        cidx = np.clip(np.searchsorted(edges, cs, side="right") - 1, 0, bins - 1)
        s_tt = output.read_array(inc_dir / "stress_zz.cell.txt")[on_wall]
        s_zz = output.read_array(inc_dir / "stress_yy.cell.txt")[on_wall]
        hoop = [float(np.mean(s_tt[cidx == i])) if np.any(cidx == i) else float("nan") for i in range(bins)]
        axial = [float(np.mean(s_zz[cidx == i])) if np.any(cidx == i) else float("nan") for i in range(bins)]
    elif (inc_dir / "stress_xx.cell.txt").is_file():
        on_wall = np.isin(cells, wall).sum(axis=1) >= 3          # cells with a face on the wall
        c = p[cells[on_wall]].mean(axis=1)
        cx, cy = c[:, 0] - axis[0], c[:, 1] - axis[1]
        cr = np.hypot(cx, cy)
        ct, st = cx / cr, cy / cr
        S = {k: output.read_array(inc_dir / f"stress_{k}.cell.txt")[on_wall] for k in ("xx", "yy", "zz", "xy")}
        s_tt = S["xx"] * st ** 2 + S["yy"] * ct ** 2 - 2 * S["xy"] * st * ct
        cs = height - c[:, 2]
        cidx = np.clip(np.searchsorted(edges, cs, side="right") - 1, 0, bins - 1)
        hoop = [float(np.mean(s_tt[cidx == i])) if np.any(cidx == i) else float("nan") for i in range(bins)]
        axial = [float(np.mean(S["zz"][cidx == i])) if np.any(cidx == i) else float("nan") for i in range(bins)]
    return {"depth": mid.tolist(), "diameter_error": d_err, "hoop_stress": hoop, "axial_stress": axial}


def write_csv(path: Path, rows: list[dict]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, keys)
        w.writeheader()
        w.writerows(rows)


def _time_axis(ax, t) -> None:
    """Time in s; logarithmic when the cooling lasts far longer than the drilling."""
    ax.set_xlabel("time [s]")
    if len(t) > 1 and t[0] > 0 and t[-1] / t[0] > 100:
        ax.set_xscale("log")


def plots(root: Path, rows: list[dict], probes: list[dict], profiles: list[dict]) -> None:
    """PNGs: probe temperatures, bore diameter error and wall stresses along the depth, energies."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    if probes:
        fig, ax = plt.subplots(figsize=(6, 4))
        t = [p["time"] for p in probes]
        for n in [k for k in probes[0] if k != "time"]:
            ax.plot(t, [p[n] for p in probes], marker=".", label=n)
        _time_axis(ax, t)
        ax.set_ylabel("temperature [K]")
        ax.set_title("thermocouples")
        ax.legend()
        fig.subplots_adjust(left=0.14, right=0.97, bottom=0.13, top=0.92)     # fixed margins: tight_layout
        fig.savefig(root / "probes.png", dpi=100)                              # cost 0.15 s a figure
        plt.close(fig)
    if profiles:
        fig, axes = plt.subplots(1, 2, figsize=(9, 4))
        drilled = [p for p in profiles if p["kind"] != "cool"]
        for p, label in ((drilled[-1] if drilled else None, "end of drilling"), (profiles[-1], "after cooling")):
            if p is None:
                continue
            depth_mm = np.array(p["depth"]) * 1e3
            axes[0].plot(np.array(p["diameter_error"]) * 1e6, depth_mm, marker="o", label=label)
            axes[1].plot(np.array(p["hoop_stress"]) / 1e6, depth_mm, marker="o", label=f"hoop, {label}")
            axes[1].plot(np.array(p["axial_stress"]) / 1e6, depth_mm, marker="x", label=f"axial, {label}")
        axes[0].set_xlabel("diameter error 2 u_r [um]")
        axes[1].set_xlabel("stress at the wall [MPa]")
        for a in axes:
            a.set_ylabel("depth below the entry face [mm]")
            a.invert_yaxis()
            a.legend(fontsize=7)
        fig.subplots_adjust(left=0.09, right=0.98, bottom=0.13, top=0.96, wspace=0.3)
        fig.savefig(root / "bore.png", dpi=100)
        plt.close(fig)
    fig, ax = plt.subplots(figsize=(6, 4))
    t = [r["time"] for r in rows]
    ax.plot(t, np.cumsum([r["heat_in"] for r in rows]), label="heat in (flux)")
    ax.plot(t, [r["energy"] for r in rows], label="in the body")
    ax.plot(t, np.cumsum([r["chips_heat"] for r in rows]), label="left with the chips")
    ax.plot(t, -np.cumsum([r["convection"] for r in rows]), label="convection losses")
    _time_axis(ax, t)
    ax.set_ylabel("energy [J]")
    ax.legend()
    fig.subplots_adjust(left=0.14, right=0.97, bottom=0.13, top=0.96)
    fig.savefig(root / "energy.png", dpi=100)
    plt.close(fig)
