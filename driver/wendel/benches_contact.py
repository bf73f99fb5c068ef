"""Benchmark ``obstacle``: deal.II step-41 (workflows/obstacle.toml) at 3 mesh sizes: PDAS active-set
iterations, DoFs and wall time (the function lives with the problem, ``blocks/contact.py``)."""

from __future__ import annotations

from .bench import register
from .blocks.contact import bench_obstacle

register("obstacle")(bench_obstacle)
