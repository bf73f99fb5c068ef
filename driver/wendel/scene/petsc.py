"""Scene keys of the PETSc solver (``numerics.solver = "petsc"``) and the check of its options string.

The preconditioner is a name of the presets in ``edp/lib/petsc.idp``; the options string reaches PETSc's
option parser through FreeFEM as one string argument, never as code, and only after this check: tokens come
in ``-name value`` pairs of a safe character set, and no option may read or write files.

>>> check_options("-ksp_rtol 1e-8 -pc_hypre_boomeramg_interp_type ext+i")
'-ksp_rtol 1e-8 -pc_hypre_boomeramg_interp_type ext+i'
>>> check_options("-ksp_type cg;reboot")
Traceback (most recent call last):
...
ValueError: value 'cg;reboot' of -ksp_type: only letters, digits and _ . + , - are allowed
"""

from __future__ import annotations

import re

from .blocks import choice

# Presets of edp/lib/petsc.idp (CG on the masked, symmetric Newton matrix, block size = dimension).
PRECONDITIONERS = {"ml": "Trilinos ML with the rigid-body modes, its own Richardson + SSOR smoothing (default)",
                   "gamg": "PETSc's smoothed-aggregation AMG with the rigid-body modes, Chebyshev smoothing",
                   "hypre": "BoomerAMG (HMIS, ext+i, Chebyshev smoothing)",
                   "jacobi": "point Jacobi (for comparisons)"}
PcName = choice(PRECONDITIONERS, "preconditioner")

_NAME = re.compile(r"-[A-Za-z][A-Za-z0-9_]*")
_VALUE = re.compile(r"-?[A-Za-z0-9_.+][A-Za-z0-9_.+,-]*")
# Options that read or write files (viewers, logs, option files) or start programs (debuggers) are refused.
_FILE_WORDS = ("options_file", "view", "log", "history", "dump", "draw", "save", "load", "info", "debugger", "malloc",
               "python")


def check_options(text: str) -> str:
    """Return ``text`` if it is ``-name value`` pairs of the safe character set; raise ValueError otherwise."""
    tokens = text.split()
    if len(tokens) % 2:
        raise ValueError(f"{len(tokens)} tokens: give -name value pairs (e.g. \"-ksp_rtol 1e-8\")")
    for name, value in zip(tokens[::2], tokens[1::2]):
        if not _NAME.fullmatch(name):
            raise ValueError(f"{name!r} is not an option name (-letters, digits, _)")
        if any(w in name.lower() for w in _FILE_WORDS):
            raise ValueError(f"{name}: options that read or write files or start programs are not allowed")
        if not _VALUE.fullmatch(value):
            raise ValueError(f"value {value!r} of {name}: only letters, digits and _ . + , - are allowed")
    return text


def launch_options(pc: str, options: str, reuse: bool) -> list[str]:
    """FreeFEM options of the PETSc path (its -DWITHPETSC=1 switch comes from ``wendel.loop.launch.macros``).

    >>> launch_options("ml", "", True)
    ['-petsc_pc', 'ml', '-petsc_options', '-wendel_pc_reuse 1']
    """
    extra = f"-wendel_pc_reuse {int(reuse)}" + (f" {options}" if options.strip() else "")
    return ["-petsc_pc", pc, "-petsc_options", extra]
