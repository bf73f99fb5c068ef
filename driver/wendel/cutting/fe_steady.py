"""Steady state of an FE cut and the animation of its frames.

A remeshed cut is a saw-tooth: every remesh smooths the state near the edge, the forces drop in the
re-equilibration (by 25-30 % on the steel scene, measured) and recover over the next increments. Two measures:

- ``raw``: :func:`wendel.cutting.chip.steady_state` (2 % over ``length``) on the increments, the
  re-equilibrations left out (a row at the travel of the one before);
- ``cycles``: the same on the means over each remesh cycle (the increments from one re-equilibration to the
  next, re-equilibration excluded, each weighted by the travel it covers, so that a mean force is the work
  over the travel even where steps were cut), placed at the cycle's mean travel: the steady state of the cut
  seen over the remesh period, which the saw-tooth does not hide;
- ``filtered``: the same on the running means over ``length`` of travel (:func:`running_means`, the mean of each
  series over the travel before each increment), over a window of twice that length, so that two averages with
  no travel in common agree within 2 %. The view of a dynamometer: at 200 m/min one h of 150 um is 45 us of cut,
  and a piezoelectric dynamometer's natural frequency of 2-4 kHz (Kistler 9257B, its data sheet) averages over
  1-1.5 mm of travel; what is left of the remesh cycles' scatter in such a mean is below what experiments can see.

:func:`gif` writes ``chip.gif`` from the frames with Pillow.

>>> rows = [{"tool_travel_m": t * 1e-6, "Fc_N": 100.0, "Ft_N": 50.0, "chip_thickness_m": 2e-4}
...         for t in (0, 5, 5, 10, 15, 15, 20)]       # remeshed after 5 and 15 um: the 20 um cycle is cut short
>>> [(round(r["tool_travel_m"] * 1e6, 1), r["increments"]) for r in cycle_means(rows)]
[(2.5, 2), (12.5, 2)]
>>> rows = [{"tool_travel_m": t * 1e-6, "Fc_N": f, "Ft_N": 50.0, "chip_thickness_m": 2e-4}
...         for t, f in ((5, 100.0), (7.5, 300.0), (10, 300.0), (15, 100.0), (15, 50.0), (20, 100.0))]
>>> round(cycle_means(rows)[0]["Fc_N"], 6)     # 5 um at 100 N, 2.5 + 2.5 um at 300 N, 5 um at 100 N (plain mean 200)
166.666667
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from . import chip

SERIES = ("Fc_N", "Ft_N", "chip_thickness_m")


def _split(rows: list[dict]) -> list[list[dict]]:
    """The remesh cycles: runs of increments, a new one after each re-equilibration (a row at the travel of
    the row before), the re-equilibration itself left out."""
    cycles, cur = [], []
    for k, r in enumerate(rows):
        if k and abs(r["tool_travel_m"] - rows[k - 1]["tool_travel_m"]) <= 1e-12:
            if cur:
                cycles.append(cur)
            cur = []
            continue
        cur.append(r)
    if cur:
        cycles.append(cur)
    return cycles


def cycle_means(rows: list[dict], series: tuple = SERIES) -> list[dict]:
    """Per remesh cycle (the last one left out when it is shorter than the others): the mean travel and the
    means of the ``series`` (finite values only)."""
    out = []
    cycles = _split(rows)
    if len(cycles) > 1 and len(cycles[-1]) < np.median([len(c) for c in cycles[:-1]]):
        cycles = cycles[:-1]       # the last cycle, cut short by the end of the run: biased low, left out
    for c in cycles:
        m = {"tool_travel_m": float(np.mean([r["tool_travel_m"] for r in c])), "increments": len(c)}
        w = _weights(rows, c)
        for k in series:
            v = np.array([r[k] for r in c], dtype=float)
            ok = np.isfinite(v)
            m[k] = float(np.average(v[ok], weights=w[ok])) if ok.any() and w[ok].sum() > 0 else \
                float(v[ok].mean()) if ok.any() else float("nan")
        out.append(m)
    return out


def _weights(rows: list[dict], cycle: list[dict]) -> np.ndarray:
    """Each increment's share of a cycle mean: the travel it covers since the row before it (a cut step covers
    less), so that the mean of a force is the work over the travel."""
    index = {id(r): k for k, r in enumerate(rows)}
    t = [r["tool_travel_m"] for r in rows]
    return np.array([max(t[index[id(r)]] - (t[index[id(r)] - 1] if index[id(r)] else 0.0), 0.0) for r in cycle])


def running_means(rows: list[dict], length: float, series: tuple = SERIES) -> list[dict]:
    """At each increment past the first ``length`` [m] of travel (re-equilibrations left out): the mean of each
    series over the travel ``(x - length, x]`` before it, each increment's value held over the travel it covers
    since the row before (as :func:`_weights`; a window's edge takes the share of an increment inside it), NaN
    values left out of the mean.

    >>> rows = [{"tool_travel_m": t * 1e-6, "Fc_N": f, "Ft_N": 50.0, "chip_thickness_m": 2e-4}
    ...         for t, f in ((5, 100.0), (10, 300.0), (10, 50.0), (15, 200.0), (20, 200.0))]
    >>> [(round(r["tool_travel_m"] * 1e6, 6), round(r["Fc_N"], 6)) for r in running_means(rows, 10e-6)]
    [(10.0, 200.0), (15.0, 250.0), (20.0, 200.0)]
    """
    t = np.array([r["tool_travel_m"] for r in rows], dtype=float)
    s = np.concatenate(([0.0], t[:-1]))           # the travel each row's value covers: (s, t]
    vals = {k: np.array([r[k] for r in rows], dtype=float) for k in series}
    out = []
    for i, x in enumerate(t):
        if x - s[i] <= 1e-12 or x < length * (1 - 1e-9):
            continue                                # a re-equilibration, or less than one window of travel
        w = np.clip(np.minimum(t, x) - np.maximum(s, x - length), 0.0, None)
        m = {"tool_travel_m": float(x)}
        for k, v in vals.items():
            ok = np.isfinite(v) & (w > 0)
            m[k] = float(np.average(v[ok], weights=w[ok])) if ok.any() else float("nan")
        out.append(m)
    return out


def _detect(rows: list[dict], length: float, tol: float):
    ok = [r for r in rows if all(np.isfinite(r[k]) for k in SERIES)]
    if len(ok) < 2:
        return None
    s = chip.steady_state([r["tool_travel_m"] for r in ok], {k: [r[k] for r in ok] for k in SERIES}, length, tol)
    return None if s is None else {"start_m": s.start, "end_m": s.end, "values": s.values, "spreads": s.spreads}


def steady(rows: list[dict], length: float, tol: float = 0.02) -> dict:
    """The three steady-state measures (see the module): ``raw`` and ``cycles`` over a window of ``length`` [m],
    ``filtered`` (means over ``length``) over twice that; None where none is found. Also the spreads and drifts of
    each measure's last window, so that a cut that does not settle says how far off it is."""
    inc = [r for k, r in enumerate(rows) if not (k and abs(r["tool_travel_m"] - rows[k - 1]["tool_travel_m"]) <= 1e-12)]
    cyc = cycle_means(rows)
    run = running_means(rows, length)
    spans = {"raw": length, "cycles": length, "filtered": 2 * length}
    last = {name: dict.fromkeys(SERIES) for name in spans}        # None: too short a cut for the measure
    trend = {name: dict.fromkeys(SERIES) for name in spans}
    for name, rr in (("raw", inc), ("cycles", cyc), ("filtered", run)):
        if rr:
            span = spans[name]
            end = rr[-1]["tool_travel_m"]
            w = [r for r in rr if r["tool_travel_m"] >= end - span * (1 + 1e-9)]
            ok = {k: len(w) > 1 and all(np.isfinite(r[k]) for r in w) for k in SERIES}
            last[name] = {k: (float(np.ptp([r[k] for r in w])) / abs(float(np.mean([r[k] for r in w])))
                              if ok[k] else None) for k in SERIES}
            trend[name] = {k: _trend(w, k, span) if ok[k] else None for k in SERIES}
    return {"length_m": length, "tol": tol, "raw": _detect(inc, length, tol), "cycles": _detect(cyc, length, tol),
            "filtered": _detect(run, 2 * length, tol), "filtered_window_m": 2 * length,
            "cycle_means": cyc, "last_window_spreads": last, "last_window_trends": trend}


def window(rows: list[dict], length: float) -> dict:
    """The cut's figures for a campaign's table (``summary.json["outputs"]``, read by ``wendel sweep``): over the
    last ``length`` [m] of travel, the mean of each series over the increments weighted by the travel each covers
    (re-equilibrations left out: a force's mean is the work over the travel), ``steady_Fc_N``, ``steady_Ft_N``,
    ``steady_chip_m``; the spread (max - min) / mean of the remesh-cycle means inside the window
    (``*_spread``, NaN with fewer than two) and their drift over the window (``*_trend``, :func:`_trend`); the
    window [m] and its number of cycles.

    >>> rows = [{"tool_travel_m": t * 1e-6, "Fc_N": f, "Ft_N": 50.0, "chip_thickness_m": 2e-4}
    ...         for t, f in ((5, 100.0), (10, 300.0), (10, 50.0), (15, 200.0), (20, 200.0))]
    >>> w = window(rows, 10e-6)       # 10-20 um: 5 um at 200 N, 5 um at 200 N (the re-equilibration left out)
    >>> round(w["steady_Fc_N"], 6), round(w["steady_window_from_m"] * 1e6, 6)
    (200.0, 10.0)
    """
    t = np.array([r["tool_travel_m"] for r in rows], dtype=float)
    hi = float(t[-1])
    lo = hi - length
    w = np.diff(t, prepend=0.0)
    inc = (t > lo + 1e-12) & (w > 1e-12)
    cyc = [c for c in cycle_means(rows) if c["tool_travel_m"] > lo]
    out = {"steady_window_from_m": lo, "steady_window_to_m": hi, "steady_cycles": len(cyc)}
    for key, name in zip(SERIES, ("Fc_N", "Ft_N", "chip_m")):
        v = np.array([r[key] for r in rows], dtype=float)
        ok = inc & np.isfinite(v)
        c = np.array([r[key] for r in cyc], dtype=float)
        c = c[np.isfinite(c)]
        out[f"steady_{name}"] = float(np.average(v[ok], weights=w[ok])) if ok.any() else float("nan")
        out[f"steady_{name}_spread"] = float(np.ptp(c) / abs(c.mean())) if len(c) > 1 else float("nan")
        out[f"steady_{name}_trend"] = (_trend([r for r in cyc if np.isfinite(r[key])], key, length)
                                       if len(c) > 1 else float("nan"))
    return out


def reached(root: Path, rows: list[dict], found: dict | None) -> float | None:
    """The run's wall time [s] when a steady window ``found`` (:func:`steady`'s ``cycles`` or ``filtered``) closed:
    the FreeFEM launches (``checkpoint.json``) up to the one that accepted the first increment at the window's end,
    with the first mesh and the remeshes before that increment; Python's start and the report excepted. None
    without a window.

    >>> import json, tempfile
    >>> d = Path(tempfile.mkdtemp())
    >>> _ = (d / "checkpoint.json").write_text(json.dumps({"mesh_seconds": 0.5, "accepted": [[1, 0.1], [2, 0.2],
    ...     [3, 0.2], [4, 0.3]], "launches": [{"wall": 10.0, "increments": 2}, {"wall": 4.0, "increments": 0},
    ...     {"wall": 6.0, "increments": 2}], "remeshes": [{"after_increment": 2, "remesh_seconds": 1.0,
    ...     "transfer_seconds": 0.5}]}))
    >>> rows = [{"increment": float(i), "tool_travel_m": t} for i, t in ((1, 1e-6), (2, 2e-6), (3, 2e-6), (4, 3e-6))]
    >>> reached(d, rows, {"start_m": 0.0, "end_m": 2e-6}), reached(d, rows, {"start_m": 0.0, "end_m": 2.5e-6})
    (10.5, 22.0)
    """
    import json
    if not found:
        return None
    ck = json.loads((Path(root) / "checkpoint.json").read_text())
    inc = next((int(r["increment"]) for r in rows if r["tool_travel_m"] >= found["end_m"] - 1e-12),
               int(rows[-1]["increment"]))
    need = sum(1 for i, _ in ck["accepted"] if i <= inc)          # accepted increments up to it
    wall, n = ck.get("mesh_seconds", 0.0), 0
    for launch in ck["launches"]:
        if n >= need:
            break
        wall, n = wall + launch["wall"], n + launch["increments"]
    return wall + sum(r.get("remesh_seconds", 0.0) + r.get("transfer_seconds", 0.0) for r in ck.get("remeshes", [])
                      if r.get("after_increment", 0) < inc)


def _trend(rows: list[dict], key: str, length: float) -> float:
    """The change over ``length`` of travel of a least-squares line through the window, over its mean: the part
    of a spread that is a drift (a cut still settling) rather than a scatter.

    >>> round(_trend([{"tool_travel_m": t, "Fc_N": 99.0 + 2 * t} for t in (0.0, 0.5, 1.0)], "Fc_N", 1.0), 9)
    0.02
    """
    x = np.array([r["tool_travel_m"] for r in rows])
    v = np.array([r[key] for r in rows], dtype=float)
    slope = np.polyfit(x, v, 1)[0] if np.ptp(x) > 0 else 0.0
    return float(slope * length / abs(v.mean()))


def gif(frames: Path, out: Path, every: int = 1, ms: int = 200) -> Path | None:
    """An animated GIF of ``frames/inc-*.png`` (every ``every``-th); None without frames."""
    from PIL import Image

    paths = sorted(frames.glob("inc-*.png"))[::every]
    if not paths:
        return None
    images = [Image.open(p).convert("P", palette=Image.ADAPTIVE) for p in paths]
    images[0].save(out, save_all=True, append_images=images[1:], duration=ms, loop=0)
    return out
