"""The quasi-static loop of a run: load steps, FreeFEM launches, step cuts, checkpoints, progress.

:func:`run` (a scene file) and :func:`run_scene` (a validated scene) are the entry points.
"""

from .checkpoint import RunFiles, State
from .launch import entry_script, macros, options, write_tables
from .quasistatic import RESULTS, run, run_scene
from .steps import StepCutError, grow_step

__all__ = ["RESULTS", "RunFiles", "State", "StepCutError", "entry_script", "grow_step", "macros", "options", "run",
           "run_scene", "write_tables"]
