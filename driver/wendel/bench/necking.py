"""Benchmark of the necking bar (``wendel bench necking``): Simo's round bar in tension (updated-Lagrangian,
axisymmetric, Voce saturation hardening) on three meshes; force-elongation, neck radius and cost.

The peak force is checked against Considere's condition for a uniform bar (d sigma_y / d eps = sigma_y, the
elastic strain neglected): the bar's peak lies between the Considere force of its smallest section (at the
imperfection, radius 0.982 R) and that of the full section.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..results import vtu as output
from ..scene import load
from . import WORKFLOWS, register, run_fresh

R0 = 6.413e-3              # m, radius of the bar (Simo 1988)


def voce(p: float, s0=450e6, h=129.24e6, sinf=715e6, delta=16.93) -> tuple[float, float]:
    """sigma_y(p) and its slope (Pa) of the necking bar's saturation law."""
    e = math.exp(-delta * p)
    return s0 + h * p + (sinf - s0) * (1 - e), h + (sinf - s0) * delta * e


def considere(radius: float) -> tuple[float, float]:
    """(log strain, force in N) at the peak of a uniform bar of this radius: sigma_y'(eps) = sigma_y(eps)."""
    lo, hi = 0.0, 2.0
    for _ in range(200):                  # bisection on sigma_y' - sigma_y, decreasing
        mid = (lo + hi) / 2
        s, ds = voce(mid)
        lo, hi = (mid, hi) if ds > s else (lo, mid)
    s, _ = voce(lo)
    return lo, s * math.pi * radius ** 2 * math.exp(-lo)


def curve(root: Path) -> list[dict]:
    """Per accepted increment: elongation of the whole bar (m), end force (N), neck and end radii (m)."""
    rows = []
    for d in sorted((root / "fem").glob("inc-*")):
        rec = json.loads((d / "record.json").read_text())
        pos = output.read_array(d / "position.node.txt").reshape(-1, 2)
        X = pos - output.read_array(d / "u_total.node.txt").reshape(-1, 2) if (d / "u_total.node.txt").is_file() \
            else pos - output.read_array(d / "u.node.txt").reshape(-1, 2)
        mid, top = np.abs(X[:, 1]) < 1e-9, np.abs(X[:, 1] - X[:, 1].max()) < 1e-9
        rows.append({"elongation": 2 * (pos[top, 1].max() - X[:, 1].max()), "force": rec["reaction_y_4"],
                     "neck_radius": pos[mid, 0].max(), "end_radius": pos[top, 0].max(),
                     "newton": rec.get("newton_iterations", 0)})
    return rows


def at(rows: list[dict], key: str, elongation: float) -> float:
    """``key`` interpolated at an elongation (m) of the curve."""
    e = [r["elongation"] for r in rows]
    return float(np.interp(elongation, e, [r[key] for r in rows])) if e and e[-1] >= elongation - 1e-12 else math.nan


@register("necking")
def necking_bench(quick: bool, workdir: Path) -> list[dict]:
    """workflows/ul-necking-bar.toml at three mesh sizes (h outside the neck zone, h_neck in it; --quick: the
    two coarser), with F-bar (the scene's kinematics.volumetric) and with the P1 cell's own volume change;
    70 increments to 14 mm."""
    levels = [(2.0e-3, 0.8e-3), (1.0e-3, 0.4e-3), (0.5e-3, 0.2e-3)]
    if quick:
        levels = levels[:2]
    path = WORKFLOWS / "ul-necking-bar.toml"
    _, f_full = considere(R0)
    eps_c, f_neck = considere(0.982 * R0)
    rows = []
    for volumetric in ("fbar", "cell"):
        for h, hn in levels:
            scene = load(path)
            scene.geometry.h = h
            scene.geometry.params["refine"]["h"] = hn
            scene.kinematics.volumetric = volumetric
            scene.output.png = False
            scene.output.vtu = False
            out = workdir / f"{volumetric}-h{h * 1e3:g}mm"
            s = run_fresh(scene, path, out)
            c = curve(out)
            peak = max(c, key=lambda r: r["force"])
            rows.append({"volumetric": volumetric, "h_mm": h * 1e3, "h_neck_mm": hn * 1e3, "dofs": s["dofs"],
                         "increments": s["increments"], "newton_iterations": s["newton_iterations"],
                         "wall_s": round(s["wall_time"], 2),
                         "peak_force_kN": peak["force"] / 1e3, "peak_at_mm": peak["elongation"] * 1e3,
                         "considere_neck_kN": f_neck / 1e3, "considere_full_kN": f_full / 1e3,
                         **{f"r_neck/R0_{e:g}mm": at(c, "neck_radius", e * 1e-3) / R0 for e in (7, 10, 12, 14)},
                         **{f"force_{e:g}mm_kN": at(c, "force", e * 1e-3) / 1e3 for e in (7, 10, 12, 14)},
                         "r_end/R0_14mm": at(c, "end_radius", 14e-3) / R0})
            (workdir / f"curve-{volumetric}-h{h * 1e3:g}mm.json").write_text(json.dumps(c))
    return rows


REMESH_AT = [35, 45, 52, 57, 61, 64, 67]   # increments after which the remeshed runs remesh (and on quality)
# (h, h_neck, remesh (h, h_min) or None, ends held radially), m, of the scene before scaling
FINE_CASES = [(2.0e-3, 0.8e-3, None, False), (0.35e-3, 0.14e-3, None, False),
              (2.0e-3, 0.8e-3, (2.0e-3, 0.4e-3), False), (1.0e-3, 0.4e-3, (1.0e-3, 0.2e-3), False),
              (0.5e-3, 0.2e-3, (0.5e-3, 0.1e-3), False), (1.0e-3, 0.4e-3, None, True)]


def scaled(scene, s: float):
    """The scene with every length times ``s``: a rate-independent bar without body force deforms alike, so
    r / R0 and the elongation / s are unchanged and forces scale by s^2. FreeFEM's mesh reader refuses
    triangles under 1e-8 in area (absolute), which in metres stops h_neck below ~0.16 mm."""
    g = scene.geometry
    g.h *= s
    prm = g.model_extra
    prm["radius"] *= s
    prm["length"] *= s
    ref = prm["refine"]
    prm["refine"] = {"box": [[c * s for c in p] for p in ref["box"]], "thickness": ref["thickness"] * s,
                     "h": ref["h"] * s}
    scene.boundary["top"].uy *= s
    if scene.remesh is not None:
        scene.remesh.h *= s
        scene.remesh.h_min *= s
    return scene


@register("necking-fine")
def necking_fine_bench(quick: bool, workdir: Path) -> list[dict]:
    """The F-bar necking bar beyond ``necking``'s meshes, on the bar scaled by 1000 in length (see
    :func:`scaled`): a fixed mesh with h_neck = 0.14 mm, and remeshed runs (after the increments of
    ``REMESH_AT`` and on quality; new meshes of the current configuration graded by p from h to h_min) from
    the 2 / 0.8, 1 / 0.4 and 0.5 / 0.2 mm starts (h_min 0.4, 0.2, 0.1 mm), and the 1 / 0.4 mm mesh with its
    moving end held radially (--quick: the first two rows). About 3 minutes (2 min 52 s in session 13)."""
    from ..scene.schema import Remesh

    S = 1000.0
    path = WORKFLOWS / "ul-necking-bar.toml"
    cases = FINE_CASES
    if quick:
        cases = cases[:2]
    rows = []
    for h, hn, rm, clamped in cases:
        scene = load(path)
        scene.geometry.h = h
        scene.geometry.params["refine"]["h"] = hn
        if rm is not None:
            scene.remesh = Remesh(at=REMESH_AT, h=rm[0], h_min=rm[1], max_remeshes=40)
        if clamped:             # u_r = 0 on the moving end (a rigid grip) instead of a frictionless one
            scene.boundary["top"].ux = 0.0
        scene.output.png = False
        scene.output.vtu = False
        scaled(scene, S)
        name = f"h{h * 1e3:g}mm-hn{hn * 1e3:g}mm" + (f"-remesh{rm[1] * 1e3:g}mm" if rm else "") + (
            "-clamped" if clamped else "")
        out = workdir / name
        s = run_fresh(scene, path, out)
        c = [{**r, "elongation": r["elongation"] / S, "force": r["force"] / S ** 2, "neck_radius": r["neck_radius"] / S,
              "end_radius": r["end_radius"] / S} for r in curve(out)]
        peak = max(c, key=lambda r: r["force"])
        rem = s.get("remeshes") or []
        rows.append({"h_mm": h * 1e3, "h_neck_mm": hn * 1e3, "remesh_h_min_mm": rm[1] * 1e3 if rm else 0.0,
                     "ends": "clamped" if clamped else "frictionless",
                     "remeshes": len(rem), "dofs_last_mesh": s["dofs"],
                     "max_residual_after_transfer": max((r["residual_after_transfer"] for r in rem), default=0.0),
                     "increments": s["increments"], "newton_iterations": s["newton_iterations"],
                     "wall_s": round(s["wall_time"], 2), "peak_force_kN": peak["force"] / 1e3,
                     **{f"r_neck/R0_{e:g}mm": at(c, "neck_radius", e * 1e-3) / R0 for e in (7, 10, 12, 14)},
                     **{f"force_{e:g}mm_kN": at(c, "force", e * 1e-3) / 1e3 for e in (7, 10, 12, 14)}})
        (workdir / f"curve-{name}.json").write_text(json.dumps(c))
    return rows
