"""Resume of a drilling run: after every completed removal step (and after the cooling) the process state is kept
in ``drilling-state.json``; ``wendel run --resume`` restores it, drops what a killed step left half done (FreeFEM
increments, VTU files, history rows, meshes and transfer folders past the last completed step) and goes on with
the next step. Completed steps are never recomputed.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

from ..remesh import mesher
from ..results import summary as report

FILE = "drilling-state.json"
KEEP = ("rows", "probes", "profiles", "energy_prev", "heat_boundary_prev", "heat_te_prev", "heat_pl_prev", "depth_prev")


def save(proc, done: int, cooled: bool) -> None:
    """Keep the state after removal step ``done`` (``cooled``: the cooling is done too), atomically."""
    st = proc.state
    data = {"done": done, "cooled": cooled, **{k: getattr(proc, k) for k in KEEP},
            "state": {"accepted": st.accepted, "segments": st.segments, "remeshes": st.remeshes,
                      "launches": st.launches, "quality": {str(k): v for k, v in st.quality.items()},
                      "post_seconds": st.post_seconds}}
    path = proc.files.root / FILE
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(data))
    os.replace(tmp, path)


def restore(proc) -> tuple[int, bool]:
    """Put the kept state back into ``proc`` and clear what came after it; return (steps done, cooled)."""
    root = proc.files.root
    data = json.loads((root / FILE).read_text())
    for k in KEEP:
        setattr(proc, k, data[k])
    st, kept = proc.state, data["state"]
    st.accepted = [tuple(a) for a in kept["accepted"]]
    st.segments, st.remeshes, st.launches = kept["segments"], kept["remeshes"], kept["launches"]
    st.quality = {int(k): v for k, v in kept["quality"].items()}
    st.post_seconds, st.pending = kept["post_seconds"], []
    last, done = st.last[0], data["done"]
    number = lambda p: int("".join(c for c in p.stem if c.isdigit()) or 0)
    for d in proc.files.fem.glob("inc-*"):
        if d.is_dir() and number(d) > last:
            shutil.rmtree(d)
    for f in proc.files.vtu.glob("inc-*.vtu"):
        if number(f) > last:
            f.unlink()
    report.truncate_history(root, last)
    for f in (root / "meshes").glob("step-*.msh"):
        if number(f) > done:
            f.unlink()
    for f in (root / "remesh").glob("*"):
        if number(f) > done:
            shutil.rmtree(f) if f.is_dir() else f.unlink()
    pts, _, cells, _, facets, tags = mesher.read_mesh(root / st.segments[-1]["mesh"])
    proc.mesh = {"points": pts, "cells": cells, "facets": facets, "tags": tags}
    return done, data["cooled"]


def resumable(root: Path) -> bool:
    return (Path(root) / FILE).is_file()
