"""The mesh cache on the step-42 ball (``wendel bench meshcache``, opt-in; about 3 minutes under the lock).

workflows/ball-indent.toml at h = 0.05 (119,016 DoFs; 0.1 = 17,490 with --quick), PETSc-ML, compiled kernels,
inexact Newton (the "forcing ew" row of ``step42-pair``), run three times in this order: with an empty cache
(cold: gmsh meshes and the mesh is stored), deal.II's step-42 (5 global refinements, 107,811 DoFs; 4 with
--quick) and with the cache the cold run filled (warm: the mesh is copied). A warm cache is what the runs of a
sweep or a study after the first one see (``WENDEL_MESH_CACHE=DIR`` or ``--mesh-cache DIR``), not a first run.
Each wendel row gives the meshing phase and the whole run, and both runs' ratio to the deal.II run.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

from ..meshes.cache import ENV
from . import register
from .step42 import _dealii_build
from .step42_pair import _dealii_row, _wendel_row


def _cached_row(out: Path, h: float, cache: Path, **scene) -> dict:
    old = os.environ.get(ENV)
    os.environ[ENV] = str(cache)
    try:
        row = _wendel_row(out, h, "ew", **scene)
    finally:
        if old is None:
            os.environ.pop(ENV, None)
        else:
            os.environ[ENV] = old
    s = json.loads((out / "summary.json").read_text())
    c = s["mesh_cache"]
    return {"code": f"wendel ball, {'warm' if c['hit'] else 'cold'} mesh cache", "dofs": row["dofs"],
            "newton_iterations": row["newton_iterations"], "contact_force": row["contact_force"],
            "mesh_s": s["wall_time_by_phase"]["mesh"], "wall_time": row["wall_time"], "cache_hit": c["hit"],
            "key": c["key"][:16]}


@register("meshcache")
def meshcache(quick: bool, workdir: Path) -> list[dict]:
    """Ball with a cold cache, deal.II step-42, ball with the warm cache (see the module docstring)."""
    exe = _dealii_build(workdir)
    refinements, h = (4, 0.1) if quick else (5, 0.05)
    cache = workdir / "cache"
    shutil.rmtree(cache, ignore_errors=True)
    cold = _cached_row(workdir / "wendel-cold", h, cache)
    d = _dealii_row(exe, workdir / "dealii", refinements)
    d.pop("sections", None)
    warm = _cached_row(workdir / "wendel-warm", h, cache)
    assert not cold["cache_hit"] and warm["cache_hit"], "the second run must find the first one's mesh"
    for r in (cold, warm):
        r["wall_time_vs_dealii"] = r["wall_time"] / d["wall_time"]
    warm["mesh_saved_s"] = cold["mesh_s"] - warm["mesh_s"]
    return [cold, {k: d[k] for k in ("code", "dofs", "newton_iterations", "contact_force", "wall_time")}, warm]
