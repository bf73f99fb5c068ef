"""A remesh made again when its re-equilibration fails: the same deformed body, the same sizes, other triangles.

Whether the re-equilibration after a remesh converges depends on the mesh (measured on the FE cut: at an
edge size of r/1 and r/3 a re-equilibration failed even in 64 stages where the other resolutions went on).
"""

from __future__ import annotations


AGAIN = (5, 1)      # gmsh 2D algorithms (Delaunay, MeshAdapt) of a remesh made again after its re-equilibration failed


def can_mesh_again(rep: dict) -> bool:
    """Whether the body of remesh report ``rep`` has a gmsh 2D algorithm of ``AGAIN`` left to be meshed with."""
    return rep.get("dimension") == 2 and rep.get("algorithm_2d_tries", 0) < len(AGAIN)


def remesh_again(scene, files, state, progress, what: str = "the re-equilibration failed",
                 pending: list | None = None) -> bool:
    """The re-equilibration after the last remesh failed even in the most stages: mesh the same deformed body
    again with the next gmsh 2D algorithm of ``AGAIN`` (the same sizes, other triangles; whether a
    re-equilibration converges depends on the mesh: measured on the FE cut) and re-equilibrate that. False when
    every algorithm has been tried (or in 3D). ``pending``: the load factors to go on with (default: those after
    the remesh's own, :func:`drop_last_remesh`)."""
    rep = state.remeshes[-1]
    tried = rep.get("algorithm_2d_tries", 0)
    if not can_mesh_again(rep):
        return False
    drop_last_remesh(state, pending)
    progress(f"  increment {rep['after_increment']}: {what}; meshing again with gmsh algorithm {AGAIN[tried]}")
    from .step import maybe_remesh
    maybe_remesh(scene, files, state, 2, progress, again=tried + 1, failed=rep.get("after_failed_step", False))
    return True


def drop_last_remesh(state, pending: list | None = None) -> dict:
    """Undo the last remesh whose re-equilibration failed (its report, mesh segment and re-equilibration load
    factor, or ``pending`` instead of what follows them): the loop stands after the increment it was made from,
    on the mesh before it. Its report."""
    rep = state.remeshes.pop()
    state.segments.pop()
    if pending is None:
        del state.pending[:1 + len(rep.get("first_steps", []))]
    else:
        state.pending = pending
    state.reequilibrate = False
    return rep


def made_or_failed(remesh, k: int, inc: int, lf: float, quality: dict, root, tries: list = (None,),
                   progress=print) -> tuple[dict, int]:
    """``remesh(algorithm)`` (remesh ``k`` after increment ``inc``) with each gmsh 2D algorithm of ``tries`` in turn
    (None: gmsh's default) until one makes a mesh of the deformed body; the report and the index of the one that did.
    When none does (gmsh's own errors, a :class:`wendel.remesh.limit.MeshTimeout`, numpy's "need at least one array
    to concatenate" on an empty mesh), a :class:`wendel.errors.RemeshFailure` (a run failure, exit 1) that names the
    remesh, the increment and its element ``quality`` and says what to do; a full disk stays what it is."""
    for i, algorithm in enumerate(tries):
        try:
            return remesh(algorithm), i
        except OSError:
            raise
        except Exception as exc:
            if i + 1 == len(tries):
                from ..errors import RemeshFailure
                raise RemeshFailure.at(k, inc, lf, quality, root, exc) from exc
            progress(f"  remesh {k}: {type(exc).__name__}: {exc}; meshing with gmsh algorithm {tries[i + 1]}")
    raise ValueError("made_or_failed: no gmsh algorithm to try")
