"""The first FreeFEM launch of a quasi-static run started while gmsh meshes (issue 20).

A new run's first launch paid FreeFEM's start (process, Open MPI's singleton, plugins, compiling the entry
script: 0.15-0.3 s here) after gmsh had meshed. Its command line does not depend on the mesh, only on the
scene and the dimension: :func:`ahead` starts it at its gate (:mod:`wendel.prestart`) before the mesh is
built, and :func:`take` hands it to the run's first ``freefem.run``, which says "go" once the mesh and
tables are written (and stops it unused if the command line it is asked for differs: the launch FreeFEM
runs is always the one asked for). Only where the dimension is known before meshing (a mesh file, or a
builder below); a resumed run starts as before. ``WENDEL_PRESTART=0`` turns it off.
"""

from __future__ import annotations

import contextlib
from pathlib import Path

from .. import prestart
from ..remesh import batch as remesh_batch
from . import separated
from .checkpoint import RunFiles, State
from .launch import options, write_tables

BUILDER_DIMENSION = {"rectangle": 2, "ring": 2, "disk": 2, "parallelogram": 2, "notched_plate": 2,
                     "cook_membrane": 2, "axi_rectangle": 2, "hollow_cylinder_section": 2,
                     "sphere_section": 2, "notched_bar": 2, "box": 3}
"""Builders whose dimension is known before they run (``meshes/``); others are not started ahead."""

_HELD: dict[Path, prestart.Started] = {}


def planned_dimension(scene) -> int | None:
    """The mesh's dimension before it is built, or None when only the builder knows it."""
    g = scene.geometry
    return g.dimension if g.builder is None else BUILDER_DIMENSION.get(g.builder)


def command(scene, files: RunFiles, dimension: int) -> tuple[str, list[str]]:
    """Entry and options of a new run's first launch (as :func:`wendel.loop.quasistatic.solve` makes them)."""
    state = State(pending=scene.loading.load_factors())
    seg = state.segment(1)
    seg_scene, entry, switches, extra = separated.launch(scene, seg, dimension)
    _, stop_args = remesh_batch.plan(scene, state, dimension)
    write_tables(scene, files, dimension)          # written again by solve: motion.txt decides an option
    opts = options(seg_scene, files, dimension, seg) + extra + ["-loads", str(files.tables / "loads.txt"),
                                                                "-inc0", "1"]
    return entry, switches + stop_args + opts


@contextlib.contextmanager
def ahead(scene, files: RunFiles):
    """Start the first launch of the new run in ``files`` at its gate; stop it on leaving if not taken."""
    dimension = planned_dimension(scene)
    if dimension is not None and scene.numerics.ranks == 1:
        entry, opts = command(scene, files, dimension)
        started = prestart.start(entry, opts, files.fem, log=files.root / "freefem.log")
        if started is not None:
            _HELD[files.root] = started
    try:
        yield
    finally:
        prestart.abandon(_HELD.pop(files.root, None))


def take(files: RunFiles) -> prestart.Started | None:
    """The launch :func:`ahead` started for this run (once; None if none)."""
    return _HELD.pop(files.root, None)
