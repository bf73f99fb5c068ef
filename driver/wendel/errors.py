"""The ways a run stops short, as exceptions the command line turns into exit codes and messages.

Kept apart from the loop so that ``wendel check`` can name them without importing the solver side.
"""

from __future__ import annotations

from pathlib import Path


class StepCutError(RuntimeError):
    """An increment failed after every allowed step cut; accepted increments are on disk."""


class RemeshFailure(StepCutError):
    """gmsh made no mesh of the deformed body at a remesh (a run failure, exit 1, not bad input); the accepted
    increments are on disk."""

    @classmethod
    def at(cls, k: int, inc: int, lf: float, quality: dict, root: Path, exc: Exception) -> "RemeshFailure":
        """The failure of remesh ``k`` after increment ``inc`` (load factor ``lf``) whose deformed mesh had the
        ``quality`` (``min_quality``, ``inverted``), caused by ``exc``, in the run folder ``root``."""
        q = quality.get("min_quality", float("nan"))
        return cls(f"remesh {k} after increment {inc} (load factor {lf:.6g}): no new mesh of the deformed body was "
                   f"made (its worst element quality {q:.3g}, {quality.get('inverted', 0)} inverted; "
                   f"{type(exc).__name__}: {exc}). The accepted increments up to {inc} are kept in {root}. Remesh "
                   f"more often (remesh.at, remesh.min_quality above {q:.2g}; a cutting scene: a smaller "
                   f"cutting.remesh_every) or take smaller increments")


class Interrupted(KeyboardInterrupt):
    """Ctrl-C or SIGTERM stopped the run in ``root``; FreeFEM was stopped too and the run can resume."""

    def __init__(self, root: Path):
        super().__init__(f"interrupted; resume with `wendel run --resume {root}`")
        self.root = root


class DiskFull(OSError):
    """The disk of the run folder ``root`` is full; accepted increments are kept and the run can resume."""

    def __init__(self, root: Path):
        super().__init__(f"disk full under {root}: the accepted increments are kept; free some space and "
                         f"resume with `wendel run --resume {root}`")
        self.root = root


class RunFolderError(ValueError):
    """The run folder (``--out``) cannot be used."""
