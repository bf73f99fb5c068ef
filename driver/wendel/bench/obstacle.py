"""Benchmark ``obstacle``: deal.II step-41 (workflows/obstacle.toml) at 3 mesh sizes: PDAS active-set
iterations, DoFs and wall time (the function lives with the problem, ``scene/blocks/contact.py``)."""

from __future__ import annotations

from ..scene.blocks.contact import bench_obstacle
from . import register

register("obstacle")(bench_obstacle)
