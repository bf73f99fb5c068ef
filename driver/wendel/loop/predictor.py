"""The extrapolated first guess (``numerics.predictor = "extrapolate"``) across FreeFEM launches.

Within a launch, ``edp/lib/predictor.idp`` starts each increment from u_n + s (u_n - u_{n-1}), the last
increment's displacement increment scaled to the load step. A launch's first increment had no such guess and
started from u_n: on the FE cut that is the retry after every step cut (the half step, from u_n, with the tool
5 um deep in the material) and the first increment that moves the tool after a remesh. :func:`options` gives
such a launch the last displacement increment as a file (``-predictor_du``), with the load step it was made
over (``-predictor_dlf``) and the load factor of the launch's start state (``-predictor_lf``):

- a restart inside a mesh segment: u_n - u_{n-1} of the two accepted increments (both on the segment's mesh);
- a re-equilibration after a remesh (and the launch after it, whose start is the re-equilibrated state): the
  old mesh's last displacement increment interpolated onto the new mesh at the deformed positions (one point
  location, :func:`wendel.remesh.transfer.transfer_nodal`), written beside the segment's transferred state.

The re-equilibration itself is at the same load factor (s = 0: no guess) and keeps the motion for the
increment after it; when that increment fails even in its smallest cut, it is tried once more without it
(the remesh's ``first_guess_carried = false``, :func:`wendel.loop.steps._without_predictor`). P1 continuous
elements only (the node files are the P1 displacement); nothing for a fresh start (increment 1), where
predictor.idp's own rule holds.
"""

from __future__ import annotations

import numpy as np

from ..results import vtu


def options(scene, files, state, dimension: int) -> list[str]:
    """The ``-predictor_*`` options of the next launch (empty when there is no motion to extrapolate)."""
    if scene.numerics.predictor != "extrapolate" or not state.accepted or not _p1(scene, dimension):
        return []
    inc, lf = state.last
    seg = state.segment(inc + 1)
    if state.reequilibrate or seg["first"] == inc:      # the segment starts at (or with) this launch's state
        if seg is state.segments[-1] and state.remeshes and state.remeshes[-1].get("first_guess_carried") is False:
            return []       # its first step failed so for good (wendel.loop.steps._without_predictor)
        got = _transferred(files, state, seg, dimension)
        if got is None:
            return []
        path, dlf = got
    else:
        if len(state.accepted) < 2 or state.accepted[-2][0] < seg["first"]:
            return []
        prev, lf_prev = state.accepted[-2]
        dlf = lf - lf_prev
        if dlf == 0:
            return []
        du = _u(files, inc) - _u(files, prev)
        path = files.tables / "predictor_du.txt"
        vtu.write_array(path, du)
    return ["-predictor_du", str(path), "-predictor_dlf", repr(float(dlf)), "-predictor_lf", repr(float(lf))]


def _transferred(files, state, seg: dict, dimension: int):
    """The last displacement increment of the mesh before ``seg``, on ``seg``'s mesh, written beside the
    segment's transferred state, and its load step; None when that mesh's last two increments made no motion.
    Made again at each launch that needs it (a remesh made again has another mesh under the same name)."""
    if not seg.get("state"):
        return None
    before = [(i, lf) for i, lf in state.accepted if i < seg["first"]]
    old = [s for s in state.segments if s["first"] < seg["first"]][-1]
    if len(before) < 2 or before[-2][0] < old["first"] or before[-1][1] == before[-2][1]:
        return None
    (n, lf_n), (m, lf_m) = before[-1], before[-2]
    from ..remesh.transfer import transfer_nodal
    X, cells = vtu.read_mesh(files.root / old["mesh"], dimension)
    Y, _ = vtu.read_mesh(files.root / seg["mesh"], dimension)
    un = _u(files, n)
    xd = X[:, :dimension] + un.reshape(-1, dimension)          # the deformed old body the new mesh was made of
    du, _ = transfer_nodal(xd, cells, (un - _u(files, m)).reshape(-1, dimension), Y[:, :dimension])
    path = files.root / seg["state"] / "predictor_du.txt"
    vtu.write_array(path, du)
    return path, lf_n - lf_m


def _u(files, inc: int) -> np.ndarray:
    return vtu.read_array(files.fem / f"inc-{inc:04d}" / "u.node.txt")


def _p1(scene, dimension: int) -> bool:
    from .launch import ELEMENT
    from ..scene import axisymmetric
    from ..scene.blocks import discretization
    return (discretization.element(scene) or axisymmetric.element(scene, dimension) or ELEMENT) == "P1"
