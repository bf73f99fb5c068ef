"""A separating DG run that goes on with CG on its remeshed bodies (``[discretization] after_separation = "cg"``).

While the run is DG, FreeFEM runs one increment per launch, so that the driver can look at each: once the faces
opened so far cut the body into two or more pieces (:func:`wendel.results.separation.split`), the driver

1. writes ``separated.msh`` (the mesh cut along the opened faces, boundary ``opened``) and ``separated.json``;
2. remeshes it in the reference configuration (small strain; :func:`wendel.remesh.mesher.remesh`: each body
   anew, the cut kept as the boundary ``opened``), size ``geometry.h``;
3. carries the state over as a remesh does (:func:`wendel.remesh.step.remesh_state`): the displacement of
   each side of the cut from its own elements' DG values (not the vertex average that ``u.node.txt`` holds),
   the total strain as the pre-strain ``eps0``; the new mesh's nodes on ``opened`` are located a hair inside
   their own side of the cut, so each side takes its own values;
4. goes on from the same load factor with CG on the new mesh: a mesh segment marked ``"discretization":
   "cg"`` (checkpoint.json), launched with the scene's CG copy (:func:`segment_scene`) and
   ``-DWITHREACTIONS=1`` (the support force, ``edp/lib/reactions.idp``); its first increment re-equilibrates
   the transferred state (``remesh/remesh-1.json``). ``opened`` has no condition: a free boundary.

history.csv keeps its columns: in the CG rows ``dg_reaction_x/y`` hold the CG support force (the same
quantity: the force on the boundaries with a non-zero prescribed displacement) and ``dg_open_faces`` /
``dg_open_length`` the cut the run separated along.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np

from ..meshes import LABELS
from ..results import separation, vtu
from .checkpoint import save

CG = "cg"


def segment_scene(scene, segment: dict):
    """The scene a mesh segment runs: the scene itself, or its CG copy after the switch."""
    if segment.get("discretization") != CG:
        return scene
    cg = scene.model_copy(deep=True)
    cg.discretization.separation_stress = 0.0
    cg.discretization.after_separation = "dg"
    cg.discretization.kind = "cg"
    return cg


def launch(scene, segment: dict, dimension: int):
    """(scene, entry script, -D switches, extra options) of a launch on ``segment``. The CG segment's residual
    scale is at least DG's largest volume-force norm (dg_scale.txt): the separated bodies carry (almost) no
    force, and a residual relative to nothing would not converge."""
    from .launch import entry_script, macros

    sc = segment_scene(scene, segment)
    switches = macros(sc, dimension)
    if segment.get("discretization") != CG:
        return sc, entry_script(sc, dimension), switches, []
    return sc, entry_script(sc, dimension), switches + ["-DWITHREACTIONS=1"], \
        ["-newton_ref_min", repr(float(segment["ref_min"]))]


def watching(scene, state) -> bool:
    """A DG run that switches to CG once separated, still DG: one increment per launch."""
    dg = getattr(scene, "discretization", None)
    return dg is not None and dg.after_separation == CG and state.segments[-1].get("discretization") != CG


def separated_bodies(files, state, inc: int) -> int:
    """Pieces the faces opened by increment ``inc`` cut the mesh into (1 when none opened)."""
    d = files.fem / f"inc-{inc:04d}"
    mids = vtu.read_array(d / "dg_open_faces.txt").reshape(-1, 2) if (d / "dg_open_faces.txt").is_file() else []
    if len(mids) == 0:
        return 1
    points, tris = vtu.read_mesh(files.root / state.segment(inc)["mesh"], 2)
    return int(separation.split(points, tris, mids)[3].max()) + 1


def maybe_switch(scene, files, state, dimension: int, progress) -> bool:
    """After an accepted DG increment: switch to CG if the body is in pieces; return whether it switched."""
    if not (watching(scene, state) and state.accepted and state.pending and not state.reequilibrate):
        return False
    inc, lf = state.last
    if separated_bodies(files, state, inc) < 2:
        return False
    switch(scene, files, state, dimension, progress)
    return True


def switch(scene, files, state, dimension: int, progress) -> None:
    """Separated mesh, remesh, transfer; the next segment is CG from the same load factor."""
    from ..remesh.step import cell_volumes, remesh_state

    inc, lf = state.last
    inc_dir = files.fem / f"inc-{inc:04d}"
    rep_sep = separation.write_separated(files.root / state.segment(inc)["mesh"], inc_dir,
                                         files.root / "separated.msh")
    # the pieces no Dirichlet boundary holds are left out (debris: no static equilibrium, the solve is singular)
    pseudo = files.root / "remesh" / "separated-increment"
    shutil.rmtree(pseudo, ignore_errors=True)
    pseudo.mkdir(parents=True)
    held = {LABELS[name] for name, b in scene.boundary.items() if any(v is not None for v in (b.ux, b.uy, b.uz))}
    keep, used = separation.keep_held(files.root / "separated.msh", pseudo / "held.msh", held)
    points, cells = vtu.read_mesh(files.root / "separated.msh", 2)
    # the increment on the cut mesh: each copy of a vertex gets the DG displacement of its own elements
    u = cut_displacement(vtu.read_array(inc_dir / "u_dg.qp.txt"), cells, len(points))
    vtu.write_array(pseudo / "u.node.txt", u[used].ravel())
    for f in inc_dir.iterdir():
        if f.name.endswith(".cell.txt") and not f.name.startswith("dg_"):
            v = vtu.read_array(f)
            vtu.write_array(pseudo / f.name, v.reshape(len(cells), -1)[keep])
    shutil.copyfile(inc_dir / "record.json", pseudo / "record.json")
    area = cell_volumes(points[:, :2], cells)
    rep_sep.update({"dropped_pieces": int(rep_sep["bodies"] - len(np.unique(_bodies(cells)[keep]))),
                    "dropped_area": float(area[~keep].sum())})
    (files.root / "separated.json").write_text(json.dumps(rep_sep, indent=1))
    mesh_new, state_dir = "meshes/mesh-1.msh", "remesh/state-1"
    h = scene.geometry.h
    rep = remesh_state(pseudo, pseudo / "held.msh", None, dimension, files.root / mesh_new,
                       files.root / state_dir, h, h / 3, "", mu=scene.material.E / (2 * (1 + scene.material.nu)),
                       deformed=False)
    rep.update({"remesh": 1, "after_increment": inc, "load_factor": lf, "relax_steps": 1, "separation": rep_sep})
    state.remeshes.append(rep)
    state.segments.append({"first": inc + 1, "mesh": mesh_new, "ubase": f"{state_dir}/ubase.txt",
                           "eps0": f"{state_dir}/eps0.txt", "state": state_dir, "discretization": CG,
                           "opened": [rep_sep["opened_faces"], rep_sep["opened_length"]],
                           "ref_min": float(vtu.read_array(inc_dir / "dg_scale.txt")[0])})
    state.pending.insert(0, lf)
    state.reequilibrate = True
    save(files, scene, state, dimension)
    dropped = rep_sep["dropped_pieces"]
    progress(f"  increment {inc}: the opened faces cut the body into {rep_sep['bodies']} pieces: separated.msh, "
             f"remeshed ({rep['new_elements']} triangles, boundary 'opened'"
             + (f"; {dropped} pieces no boundary condition holds left out, {rep_sep['dropped_area']:.3g} m^2" if dropped
                else "") + "); going on with CG")


def _bodies(cells):
    from ..remesh.bodies import body_index

    return body_index(cells)


def cut_displacement(u_dg: np.ndarray, cells: np.ndarray, n_points: int) -> np.ndarray:
    """Nodal displacement (n, 2) of the cut mesh from the P1dc DG vector (per element: x at its three vertices,
    then y): each vertex the mean of the values its elements give it (they differ by the closed faces' jumps).

    >>> cut_displacement(np.array([1., 1, 1, 0, 0, 0, 3, 3, 3, 2, 2, 2]), np.array([[0, 1, 2], [2, 1, 3]]), 4).tolist()
    [[1.0, 0.0], [2.0, 1.0], [2.0, 1.0], [3.0, 2.0]]
    """
    per = np.asarray(u_dg, dtype=float).reshape(len(cells), 2, 3)
    total = np.zeros((n_points, 2))
    count = np.zeros(n_points)
    for k in range(3):
        np.add.at(total, cells[:, k], per[:, :, k])
        np.add.at(count, cells[:, k], 1.0)
    return total / np.maximum(count, 1.0)[:, None]


def history_row(record: dict, extra: dict, segment: dict) -> dict:
    """The history.csv row of an increment: its record and ``extra``; in a CG segment the DG columns hold the CG
    support force and the cut (see the module's docstring)."""
    if segment.get("discretization") != CG:
        return {**record, **extra}
    extra = {**extra, "dg_open_faces": segment["opened"][0], "dg_open_length": segment["opened"][1]}
    for a in "xy":
        if f"reaction_{a}" in record:
            extra[f"dg_reaction_{a}"] = record[f"reaction_{a}"]
    return {**record, **extra}
