"""``wendel bench cutting-steady-mesh``: the mesh study of the settled F-bar cut with conduction (issue 17).

``cutting-mesh`` compares the edge resolutions over 240-400 um of travel, while the cut still builds up (its
forces there are 8-10 % above those of the settled cut). This bench compares them where the cut has settled:
each edge (r/2, r/3, r/4; ``WENDEL_BENCH_EDGES``: the three of ``cutting-mesh``, its fourth ignored) cuts 1.2 mm
(8 h) with F-bar and conduction, exactly ``WENDEL_BENCH_EDGE=<n> WENDEL_BENCH_CONDUCTION=1 wendel bench
cutting-steady-fbar`` and in that bench's folders (``results/bench/work/cutting-steady-fbar/r<n>-long-conduction``,
where a finished cut of the same scene is read, not run again: each takes 1-3 h here). Each is measured over
its last ``WINDOW`` of travel (300 um, 2 h; 20 remesh cycles at r/3, remeshed also on quality) by
:func:`wendel.bench.cutting_mesh.measure` (the means weighted by travel, the spread of the remesh-cycle means),
with the drift of those cycle means over the window (:func:`wendel.cutting.fe_steady.window`'s ``*_trend``: a
cut still settling drifts); ``dFc``, ``dFt``, ``dchip``: the change from the next coarser edge. ``--quick``: 400 um
cuts in this bench's own folder, the last 100 um. ``WENDEL_BENCH_MUMPS=1``: the cuts with MUMPS (folders ``...-mumps``)."""

from __future__ import annotations

import csv
from pathlib import Path

from . import edges, env_flag, environ, register

WINDOW = 300e-6     # m: the last 2 h of the 1.2 mm
DEFAULT = [("r/2", 2, 1), ("r/4", 4, 1), ("r/3", 3, 1)]


@register("cutting-steady-mesh")
def cutting_steady_mesh_bench(quick: bool, workdir: Path) -> list[dict]:
    """The settled F-bar cut with conduction at three edge resolutions (see the module)."""
    from ..cutting.fe_steady import window
    from ..cutting.scene import predict
    from .cutting_mesh import _scene, _steady, measure
    divs = sorted({d for _, d, sub in edges(DEFAULT) if sub == 1})
    root = workdir / "quick" if quick else workdir.parent / "cutting-steady-fbar"
    length = 100e-6 if quick else WINDOW
    rows = []
    for d in divs:
        with environ(WENDEL_BENCH_EDGE=str(d), WENDEL_BENCH_CONDUCTION="1", WENDEL_BENCH_SNAP="0"):
            last = _steady(quick, root, "fbar", reuse=True)[-1]
        mumps = "-mumps" if env_flag("WENDEL_BENCH_MUMPS", 'numerics.direct = "mumps"') else ""
        cut = [{k: float(v) for k, v in r.items()}
               for r in csv.DictReader((root / f"r{d}-long-conduction{mumps}" / "cutting.csv").open())]
        w = window(cut, length)
        drift = {f"{n}_drift": w[f"steady_{k}_trend"] for n, k in (("Fc", "Fc_N"), ("Ft", "Ft_N"), ("chip", "chip_m"))}
        cost = {k: last[k] for k in ("increments", "step_cuts", "newton_iterations", "remeshes", "wall_s", "stopped")}
        rows.append({"edge": f"r/{d}", "edge_size_um": 20.0 / d, **measure(cut, length), **drift, **cost})
    for prev, r in zip(rows, rows[1:]):
        for n in ("Fc", "Ft", "chip"):
            r[f"d{n}"] = r[f"{n}_last"] / prev[f"{n}_last"] - 1
    ox = predict(_scene(1, 1, quick))
    rows.append({"edge": "Oxley (sharp tool)", "Fc_last": ox.Fc, "Ft_last": ox.Ft,
                 "chip_last": ox.chip_thickness * 1e6})
    return rows
