"""The driver's remeshing step: judge the deformed mesh, mesh it anew, carry the state over.

After an accepted increment on a mesh with reference coordinates X and displacement u (since that
mesh was made), the deformed mesh X + u is judged by its element quality (:mod:`wendel.remesh.quality`). When
it is too poor (or the scene asks for a remesh at that increment), gmsh meshes the deformed body anew
(:mod:`wendel.remesh.mesher`) and the state is interpolated onto the new mesh (:mod:`wendel.remesh.transfer`):

- displacement: the total displacement reached (``u_total = ubase + u``) becomes the new ``ubase``
  (Dirichlet values are measured from the original body); ``u`` restarts at zero;
- total strain (the ``strain_*`` cell fields) becomes the pre-strain ``eps0`` of the new mesh (Mandel,
  component-major), so the stress state is kept;
- module state: nodal files (``*.node.txt``, e.g. temperature) are interpolated; quadrature-point
  files (``*.qp.txt``, component-major, one point per element with P1) are recovered to nodes by a
  volume-weighted average (which keeps their integral), interpolated and averaged on the new cells;
  other state files (``*.txt``) are copied.

The driver then re-equilibrates at the same load factor before the next increment; the transfer report
(``remesh/remesh-K.json``) records the residuals, the change of the integral and extrema of p, the qualities, the times.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import sys
import time
from pathlib import Path

import numpy as np

from .again import AGAIN, made_or_failed
from .batch import first_steps
from .snap import onto_tool, tool_at, trim_at, zones_at       # the tool where it stands at a remesh (numpy only)
from . import limit, quality   # mesher (meshio, gmsh), transfer (scipy) when a run remeshes: one that does not: none
from ..results import vtu

SKIP_NODE = {"u", "u_total"}


def judge(points: np.ndarray, cells: np.ndarray, u: np.ndarray, dimension: int) -> dict:
    """Quality of the deformed mesh X + u (u interleaved per node)."""
    deformed = points[:, :dimension] + u.reshape(len(points), dimension)
    q = quality.mesh_quality(deformed, cells, reference=points[:, :dimension])
    return {"min_quality": q["min"], "mean_quality": q["mean"], "inverted": q["inverted"]}


def cell_volumes(points: np.ndarray, cells: np.ndarray, axisymmetric: bool = False) -> np.ndarray:
    """Unsigned areas (2D) or volumes (3D); the volumes of revolution 2 pi r_centroid |K| of (r, z) cells.

    >>> pts = np.array([[0., 0], [3, 0], [0, 1]])
    >>> round(float(cell_volumes(pts, [[0, 1, 2]])[0]), 12), round(float(cell_volumes(pts, [[0, 1, 2]], True)[0] / np.pi), 12)
    (1.5, 3.0)
    """
    vol = np.abs(quality.signed_measure(points, cells))
    if axisymmetric:
        vol = vol * 2 * np.pi * np.asarray(points)[np.asarray(cells), 0].mean(axis=1)
    return vol


def yield_violation(eps0: np.ndarray, epsp: np.ndarray, sigma_y: np.ndarray, mu: float, dimension: int) -> float:
    """Fraction of cells whose von Mises stress exceeds the yield stress after a transfer.

    ``eps0``: total strain per cell (Mandel; 2D [xx, yy, sqrt2 xy], axisymmetric [rr, zz, sqrt2 rz, theta]); ``epsp``: plastic strain per cell
    (Mandel; 2D [xx, yy, zz, sqrt2 xy], 3D as eps0). The pressure does not enter von Mises stress, so only
    the shear modulus ``mu`` is needed: s = 2 mu dev(eps - epsp).

    >>> e = np.array([[1e-3, -1e-3, 0.0]]); z = np.zeros((1, 4))
    >>> yield_violation(e, z, np.array([100e6]), 80e9, 2), yield_violation(e, z, np.array([300e6]), 80e9, 2)
    (1.0, 0.0)
    """
    if dimension == 2:
        zz = eps0[:, 3] if eps0.shape[1] == 4 else np.zeros(len(eps0))    # the hoop strain of (r, z) models
        tot = np.column_stack([eps0[:, 0], eps0[:, 1], zz, eps0[:, 2]])
        ee = tot - epsp
        normal, shear = ee[:, :3], ee[:, 3:]
    else:
        ee = eps0 - epsp
        normal, shear = ee[:, :3], ee[:, 3:]
    dev = normal - normal.mean(axis=1, keepdims=True)
    dev_norm = np.sqrt((dev ** 2).sum(axis=1) + (shear ** 2).sum(axis=1))
    vm = np.sqrt(1.5) * 2 * mu * dev_norm
    return float(np.mean(vm > sigma_y * (1 + 1e-6)))


def remesh_state(inc_dir: Path, mesh_old: Path, ubase_old: np.ndarray | None, dimension: int,
                 mesh_new: Path, state_new: Path, h: float, h_min: float, indicator: str,
                 mu: float | None = None, axisymmetric: bool = False, make_mesh=None,
                 deformed: bool = True, zones: list[dict] | None = None, algorithm_2d: int | None = None,
                 smooth_features: float = 0.0, tool: dict | None = None, trim: dict | None = None) -> dict:
    """Mesh the deformed body of increment ``inc_dir`` anew and write the transferred state.

    Writes ``mesh_new`` and, in ``state_new``, ``u.node.txt`` (zeros), ``ubase.txt``, ``eps0.txt`` and the
    module state files; returns the transfer report (without the re-equilibration residuals).
    ``axisymmetric``: (r, z) meshes: recoveries and integrals with the volumes of revolution, the hoop strain
    carried in ``eps0``.
    ``make_mesh`` replaces :func:`wendel.remesh.mesher.remesh` (same arguments and report keys), e.g. the material
    removal of :mod:`wendel.drilling`; ``deformed = False`` transfers in the reference configuration
    (small strain: the new mesh is made from the original geometry); ``zones``: boxes of finer size
    (:func:`wendel.remesh.mesher.remesh`); ``smooth_features``: :mod:`wendel.remesh.features`; ``tool``: a 2D
    rigid tool where it stands (``vertices``, ``radii``): new boundary nodes inside it are moved onto its surface
    (:mod:`wendel.remesh.snap`); ``trim``: what the new mesh leaves out (:func:`wendel.remesh.snap.trim_at`).
    """
    from . import mesher, transfer

    t0 = time.perf_counter()
    X, cells = vtu.read_mesh(mesh_old, dimension)
    X = X[:, :dimension]
    n_old = len(X)
    u = vtu.read_array(inc_dir / "u.node.txt")
    xd = X + u.reshape(n_old, dimension) if deformed else X
    before = quality.mesh_quality(xd, cells, reference=X)
    cellfield = lambda name: _cells(inc_dir / f"{name}.cell.txt", len(cells))
    size_ind = None
    if indicator and (inc_dir / f"{indicator}.cell.txt").is_file():
        size_ind = transfer.cell_to_nodes(xd, cells, cellfield(indicator)[:, 0], axisymmetric=axisymmetric)
    with _quiet_stdout():
        info = (make_mesh or mesher.remesh)(xd, mesh_old, mesh_new, h, size_indicator=size_ind, h_min=h_min,
                                            **({"zones": zones} if zones else {}), **{k: v for k, v in (
                                                ("algorithm_2d", algorithm_2d), ("smooth_features", smooth_features),
                                                ("trim", trim)) if v})
    t1 = time.perf_counter()
    Y, new_cells = vtu.read_mesh(mesh_new, dimension)
    Y = Y[:, :dimension]
    snapped = {}
    if tool is not None and dimension == 2 and deformed:
        Y, snapped = onto_tool(mesh_new, Y, new_cells, tool)
    state_new.mkdir(parents=True, exist_ok=True)
    report = {"old_nodes": n_old, "old_elements": len(cells), "new_nodes": len(Y), "new_elements": len(new_cells),
              "min_quality_before": before["min"], "inverted_before": before["inverted"],
              "min_quality_after": info["min_sicn"], "measure_old": info["measure_old"],
              "measure_new": info["measure_new"], "remesh_seconds": t1 - t0,
              "boundary_nodes_smoothed": info.get("boundary_nodes_smoothed", 0)}
    report.update({**snapped, **{k: info[k] for k in ("trimmed_elements", "trimmed_measure") if k in info}})
    # Every field goes through one point location: nodal fields as they are, cell fields recovered
    # to nodes (volume-weighted, integral kept), all stacked, interpolated once, split again.
    utot = u + (ubase_old if ubase_old is not None else 0.0)
    fields = [("node", "ubase.txt", utot.reshape(n_old, dimension)),
              ("cell", "eps0.txt", transfer.cell_to_nodes(xd, cells, mandel_strain(inc_dir, dimension, axisymmetric),
                                                          axisymmetric=axisymmetric))]
    for f in sorted(inc_dir.glob("*.node.txt")):
        if f.name.removesuffix(".node.txt") not in SKIP_NODE:
            fields.append(("node", f.name, vtu.read_array(f).reshape(n_old, -1)))
    qp_cells = {}
    for f in sorted(inc_dir.glob("*.qp.txt")):
        v = vtu.read_array(f)
        if v.size % len(cells):
            raise ValueError(f"{f}: {v.size} values are not a whole number per element; cannot transfer")
        qp_cells[f.name] = v.reshape(v.size // len(cells), len(cells)).T
        fields.append(("qp", f.name, transfer.cell_to_nodes(xd, cells, qp_cells[f.name], axisymmetric=axisymmetric)))
    widths = [a.reshape(n_old, -1).shape[1] for _, _, a in fields]
    stacked = np.hstack([a.reshape(n_old, -1) for _, _, a in fields])
    moved, outside = transfer.transfer_nodal(xd, cells, stacked, _targets(mesh_new, Y, new_cells, dimension))
    report["nodes_outside_old_mesh"] = int(outside)
    vtu.write_array(state_new / "u.node.txt", np.zeros(len(Y) * dimension))
    vol_old, vol_new = cell_volumes(xd, cells, axisymmetric), cell_volumes(Y, new_cells, axisymmetric)
    col = 0
    for (kind, name, _), w in zip(fields, widths):
        part = moved[:, col:col + w]
        col += w
        if kind == "node":
            vtu.write_array(state_new / name, part)            # interleaved per node
            continue
        per_cell = transfer.nodes_to_cells(new_cells, part)
        vtu.write_array(state_new / name, per_cell.T)          # component-major for FreeFEM
        if kind == "qp" and (name.endswith("_p.qp.txt") or name == "p.qp.txt"):
            old = qp_cells[name][:, 0]
            report["integral_p_before"] = float(vol_old @ old)
            report["integral_p_after"] = float(vol_new @ per_cell[:, 0])
            report["max_p_before"] = float(old.max())
            report["max_p_after"] = float(per_cell[:, 0].max())
    written = {name: vtu.read_array(state_new / name) for _, name, _ in fields if name.endswith(".qp.txt")}
    if mu and "plast_epsp.qp.txt" in written and "plast_sigma_y.qp.txt" in written:
        m = len(new_cells)
        eps0 = vtu.read_array(state_new / "eps0.txt").reshape(-1, m).T
        epsp = written["plast_epsp.qp.txt"].reshape(-1, m).T
        report["yield_violation_after_transfer"] = yield_violation(eps0, epsp, written["plast_sigma_y.qp.txt"], mu,
                                                                   dimension)
    for name in ("T.node.txt",):
        if (state_new / name).is_file():
            t_old = vtu.read_array(inc_dir / name)
            t_new = vtu.read_array(state_new / name)
            report["integral_T_before"] = float(vol_old @ transfer.nodes_to_cells(cells, t_old))
            report["integral_T_after"] = float(vol_new @ transfer.nodes_to_cells(new_cells, t_new))
            report["max_T_before"], report["max_T_after"] = float(t_old.max()), float(t_new.max())
    rec = json.loads((inc_dir / "record.json").read_text())
    for key in ("contact_force", "contact_active_nodes", "max_plastic_strain"):
        if key in rec:
            report[f"{key}_before"] = rec[key]
    for f in sorted(inc_dir.glob("*.txt")):
        if not f.name.endswith((".node.txt", ".cell.txt", ".qp.txt")) and not (state_new / f.name).exists():
            shutil.copyfile(f, state_new / f.name)
    report["transfer_seconds"] = time.perf_counter() - t1
    return report


def _targets(mesh: Path, Y: np.ndarray, cells: np.ndarray, dimension: int) -> np.ndarray:
    """Where the new nodes are located in the old mesh: a node on a cut (boundary ``opened``) a hair inside its
    own cells (:func:`wendel.remesh.bodies.inside_targets`), the others where they are."""
    if dimension != 2:
        return Y
    from . import bodies, mesher

    *_, facets, tags = mesher.read_mesh(mesh)
    return bodies.inside_targets(Y, cells, np.unique(facets[tags == mesher.OPENED]))


@contextlib.contextmanager
def _quiet_stdout():
    """gmsh's C++ side prints blank lines to file descriptor 1 whatever its options: send them away."""
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)


STRAIN = {2: ("xx", "yy", "xy"), 3: ("xx", "yy", "zz", "yz", "xz", "xy")}


def mandel_strain(inc_dir: Path, dimension: int, axisymmetric: bool = False) -> np.ndarray:
    """The total strain of an increment as Mandel vectors per cell (shear components x sqrt2); an (r, z) model
    adds its hoop strain last (edp/lib/axisymmetric.idp's order)."""
    comps = STRAIN[dimension] + (("hoop",) if axisymmetric else ())
    cols = [vtu.read_array(inc_dir / f"strain_{c}.cell.txt") for c in comps]
    return np.column_stack([v * (np.sqrt(2.0) if c in ("xy", "yz", "xz") else 1.0) for c, v in zip(comps, cols)])


def _cells(path: Path, n_cells: int) -> np.ndarray:
    v = vtu.read_array(path)
    return v.reshape(n_cells, -1)


def finish_report(report: dict, reeq_dir: Path, path: Path) -> dict:
    """Add the re-equilibration residuals (first and last Newton rows) and write the report."""
    rows = [r.split(",") for r in (reeq_dir / "newton.csv").read_text().splitlines()]
    head, rows = rows[0], rows[1:]
    col = head.index("relative_residual")
    report["residual_after_transfer"] = float(rows[0][col])
    report["residual_after_reequilibration"] = float(rows[-1][col])
    report["reequilibration_iterations"] = len(rows) - 1
    rec = json.loads((reeq_dir / "record.json").read_text())
    after = ("contact_force", "contact_active_nodes", "max_plastic_strain", "plastic_points")
    report.update({f"{key}_after": rec[key] for key in after if key in rec})
    report.update({k: rec[k] for k in ("relax_handovers", "relax_handover_residual") if k in rec})      # stages
    path.parent.mkdir(exist_ok=True)
    path.write_text(json.dumps(report, indent=1))
    return report


def maybe_remesh(scene, files, state, dimension: int, progress, again: int = 0, failed: bool = False) -> None:
    """The loop's remesh step: after the last accepted increment, remesh when its deformed mesh is too poor
    (or the scene asks, or the next step ``failed`` even in its smallest cut); the next launch re-equilibrates
    the transferred state at the same load factor.

    ``files`` and ``state`` are the loop's :class:`wendel.loop.checkpoint.RunFiles` and ``State``.
    """
    r = scene.remesh
    inc, lf = state.last
    if state.segments[-1]["first"] > inc:
        return      # already remeshed after this increment (a resumed run)
    q = state.quality.get(inc, {})
    poor = q.get("min_quality", 1.0) < r.min_quality or q.get("inverted", 0) > 0
    if not (poor or failed or inc in r.at):
        return
    if len(state.remeshes) >= r.max_remeshes:
        if poor:
            progress(f"  increment {inc}: mesh quality {q['min_quality']:.3g} but remesh.max_remeshes "
                     f"= {r.max_remeshes} reached; going on without remeshing")
        return
    k = len(state.remeshes) + 1
    seg = state.segment(inc)
    h = r.h or scene.geometry.h
    mesh_new = f"meshes/mesh-{k}.msh"
    state_dir = f"remesh/state-{k}"
    ubase_old = vtu.read_array(files.root / seg["ubase"]) if seg["ubase"] else None
    why = " (the next step failed)" if failed else " (asked by remesh.at)" if not poor else ""
    progress(f"  increment {inc}: min quality {q.get('min_quality', float('nan')):.3g}{why}: remeshing")
    tries = [None, *AGAIN][again:] if dimension == 2 else [None]       # gmsh's default, then the others in turn
    rep, used = made_or_failed(lambda algorithm: remesh_state(
        files.fem / f"inc-{inc:04d}", files.root / seg["mesh"], ubase_old, dimension, files.root / mesh_new,
        files.root / state_dir, h, r.h_min or h / 3, r.indicator, mu=scene.material.E / (2 * (1 + scene.material.nu)),
        axisymmetric=scene.elasticity.plane == "axisymmetric", zones=zones_at(r, files.fem / f"inc-{inc:04d}"),
        algorithm_2d=algorithm, smooth_features=r.smooth_features, make_mesh=limit.mesher(r.mesh_timeout),
        tool=tool_at(scene, files.fem / f"inc-{inc:04d}") if r.snap_to_tool else None,
        trim=trim_at(r, files.fem / f"inc-{inc:04d}")), k, inc, lf, q, files.root, tries, progress)
    rep.update({"remesh": k, "after_increment": inc, "load_factor": lf, "dimension": dimension,
                "algorithm_2d_tries": again + used, "after_failed_step": failed,
                "first_steps": first_steps(scene, lf, state.pending)})      # (drop_last_remesh takes them out)
    state.remeshes.append(rep)
    state.segments.append({"first": inc + 1, "mesh": mesh_new, "ubase": f"{state_dir}/ubase.txt",
                           "eps0": f"{state_dir}/eps0.txt", "state": state_dir})
    state.pending[:0] = [lf] + rep["first_steps"]
    state.reequilibrate = True
