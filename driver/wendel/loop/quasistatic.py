"""The quasi-static loop: build the mesh, step the load, cut steps that fail, write results, report.

:func:`run` is the table of contents; each step is a small function below it. Step control: :mod:`.steps`, FreeFEM
command: :mod:`.launch`, checkpoint: :mod:`.checkpoint`, progress: :mod:`.progress`, remesh: :mod:`wendel.remesh.step`.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
import time
from pathlib import Path

from .. import freefem
from ..cutting.fe_run import report_resumed, resumed_rule
from ..errors import DiskFull, RunFolderError
from ..meshes import build as build_mesh
from ..remesh import batch as remesh_batch
from ..remesh.step import finish_report, judge, maybe_remesh
from ..results import pictures, separation, summary, vtu
from ..scene import load
from ..scene.reading import check_size
from ..scene.schema import Scene
from .checkpoint import RunFiles, State, committed, save as _save_checkpoint
from . import overlap, predictor, separated
from .guard import disk_full as _disk_full, guarded
from .resume import is_drilling, restart, resume as resume_run, resume_drilling
from .launch import options, write_tables
from .progress import _Progress
from .steps import cut_step, grow_step, plan_step

RESULTS = freefem.ROOT / "results"


def run(scene_path: str | Path, smoke: bool = False, ranks: int | None = None, out: Path | None = None,
        resume: Path | None = None, progress=print, png: bool | None = None, scale: float | None = None) -> Path:
    """Run the scene file ``scene_path``; return the run folder (results/<scene>/<run-id>/).

    ``ranks`` and ``png`` override numerics.ranks and output.png; ``scale`` multiplies
    geometry.h and the size of a refined zone (geometry.refine.h); ``resume`` continues the run folder
    given from its last checkpoint.
    """
    if resume is not None:
        root = Path(resume).resolve()
        if is_drilling(root):
            return resume_drilling(root, progress)
        if not (root / "checkpoint.json").is_file() and (root / "scene.resolved.json").is_file():
            return restart(root, progress)
        with guarded(root):
            files, scene, state = resume_run(root, progress)
            progress(f"resuming {files.root} after increment {state.last[0]} (load factor {state.last[1]:g})")
            # a cut: its stop rule (cutting.stop_when_steady) and its cutting report
            return report_resumed(_execute(scene, files, state, progress, resumed_rule(root, progress)), progress)
    scene_path = Path(scene_path)
    scene = load(scene_path, smoke=smoke)
    if getattr(scene, "cutting", None) is not None:     # an orthogonal cut: the FE scene it derives (issue 17)
        from ..cutting.fe_run import run_cut
        return run_cut(scene, scene_path, Path(out) if out else _new_run_dir(scene_path, smoke), smoke, progress,
                       frames=png is not False)
    if scale is not None:
        scene.geometry.h *= scale
        refine = (scene.geometry.model_extra or {}).get("refine")
        if isinstance(refine, dict) and "h" in refine:
            refine["h"] *= scale
    if png is not None:
        scene.output.png = png
    if ranks is not None:
        if ranks > 1:
            scene.numerics.solver = "ffddm"      # first: the schema refuses other solvers on several ranks
        scene.numerics.ranks = ranks
    return run_scene(scene, scene_path, Path(out) if out else _new_run_dir(scene_path, smoke), smoke, progress)


def run_scene(scene: Scene, scene_path: Path, out: Path, smoke: bool = False, progress=print, record=None,
              until=None) -> Path:
    """Run an already validated scene (read from ``scene_path``) into ``out`` (``record``: write_provenance's;
    ``until``: a stop rule, asked with the state after every launch that ended well, as :func:`solve`)."""
    files = RunFiles(Path(out).resolve())      # FreeFEM runs inside the run folder: paths must be absolute
    if files.root.is_dir() and any(files.root.iterdir()):
        # never mix a new run with the files of another (nor delete them): a new folder, or --resume
        raise ValueError(f"run folder {files.root} exists and is not empty: choose another --out, or continue "
                         f"the run in it with `wendel run --resume {files.root}`")
    if files.root.exists() and not files.root.is_dir():
        raise RunFolderError(f"run folder (--out) {out}: is a file, not a folder")
    try:
        files.root.mkdir(parents=True, exist_ok=True)
        (files.root / ".write-test").touch()
        (files.root / ".write-test").unlink()
    except OSError as exc:
        raise RunFolderError(f"run folder (--out) {out}: cannot be created or written: {exc.strerror}") from None
    check_size(scene, str(scene_path))       # h may have been scaled since the scene was read (studies)
    overlap.preload("meshio")     # imported while gmsh meshes and FreeFEM starts, not at the first VTU
    if getattr(scene, "drilling", None) is not None:      # a process of removal steps: wendel.loop.drilling
        from .drilling import run as run_drilling
        with guarded(files.root):
            return run_drilling(scene, scene_path, files.root, smoke, progress)
    with guarded(files.root):
        if scene.output.png:
            pictures.prestart()        # the renderer starts while the driver meshes (issue 20)
        summary.write_provenance(files.root, Path(scene_path), scene, smoke, record)
        state = State(pending=scene.loading.load_factors())
        state.mesh_seconds, dimension = build(scene, files)
        if dimension == 2:
            pictures.plane()           # the picture process needs no matplotlib (wendel.results.flat)
        _save_checkpoint(files, scene, state, dimension)
        return _execute(scene, files, state, progress, until)


def _execute(scene: Scene, files: RunFiles, state: State, progress, until=None) -> Path:
    """Solve the pending increments, then summary and picture."""
    dimension = json.loads(files.checkpoint.read_text())["dimension"]
    overlap.preload("meshio")         # a resumed run
    progress(f"wendel: {scene.description}")
    progress(f"  run folder {files.root}")
    # the picture process starts its renderer while FreeFEM solves
    with pictures.painter(pictures.renderer(files.mesh)) if scene.output.png else contextlib.nullcontext() as painter:
        _solve_and_report(scene, files, state, dimension, progress, painter, until)
    return files.root


def _solve_and_report(scene: Scene, files: RunFiles, state: State, dimension: int, progress, painter,
                      until=None) -> None:
    """Solve, write summary.json, then the picture (the run's critical path waits for the render only)."""
    try:
        segment = state.segments[-1]
        after_reequilibration = len(state.segments) > 1 and state.last[0] == segment["first"]
        if scene.remesh and state.accepted and state.pending and not state.reequilibrate \
                and not after_reequilibration:
            maybe_remesh(scene, files, state, dimension, progress)    # a run resumed before the decision
        separated.maybe_switch(scene, files, state, dimension, progress)     # (the same, DG -> CG)
        solve(scene, files, state, dimension, progress, until)
        separation.after_run(scene, files, state, progress)
    finally:
        with contextlib.suppress(OSError):       # a full disk must not hide why the run stopped
            summary.write_summary(files.root, scene, state, dimension)
    if scene.output.png and state.accepted:
        t0 = time.perf_counter()
        inc, lf = state.last
        if scene.output.vtu:
            painter.paint(files.vtu / f"inc-{inc:04d}.vtu", files.root / "deformed.png", f"load factor {lf:g}",
                          scene.output.warp, deformed=scene.kinematics.updated_lagrangian)
        else:            # no VTU series: the picture is made from a VTU of the last increment that is not kept
            with tempfile.TemporaryDirectory() as tmp:
                vtu.write_increment(Path(tmp) / "last.vtu", files.root / state.segment(inc)["mesh"],
                                    files.fem / f"inc-{inc:04d}", dimension, scene.kinematics.updated_lagrangian)
                painter.paint(Path(tmp) / "last.vtu", files.root / "deformed.png", f"load factor {lf:g}",
                              scene.output.warp, deformed=scene.kinematics.updated_lagrangian)
        summary.write_summary(files.root, scene, state, dimension, picture=time.perf_counter() - t0)


def build(scene: Scene, files: RunFiles) -> tuple[float, int]:
    """Make the mesh (gmsh builder or a given file); return (seconds, dimension)."""
    t0 = time.perf_counter()
    g = scene.geometry
    if g.builder:
        built = build_mesh(g.builder, files.mesh, **g.params)
        dimension = built.dimension
    else:
        shutil.copyfile(g.mesh, files.mesh)
        dimension = g.dimension
    return time.perf_counter() - t0, dimension


def solve(scene: Scene, files: RunFiles, state: State, dimension: int, progress, until=None) -> None:
    """Launch FreeFEM on the pending increments (all in one launch without remeshing; with it, a launch a remeshing
    segment, ended by FreeFEM after a poor mesh: :mod:`wendel.remesh.batch`); cut failing steps; remesh. After a
    launch that ended well ``until(state)`` (if given) may end the run: the increments left are dropped."""
    write_tables(scene, files, dimension)
    if scene.remesh:            # imported while FreeFEM solves the first segment, not at the first remesh
        overlap.preload("wendel.remesh.transfer", "wendel.remesh.mesher")
    while state.pending:
        inc0 = state.last[0] + 1
        seg = state.segment(inc0)
        seg_scene, entry, switches, extra = separated.launch(scene, seg, dimension)    # CG after a DG separation
        if scene.loading.adaptive and not state.reequilibrate:
            plan_step(scene, state)
        was_reequilibration = state.reequilibrate
        batch, stop_args = remesh_batch.plan(scene, state, dimension)
        relax_cell = state.reequilibrate and state.remeshes[-1].get("relax_cell", False)     # steps.cut_step
        if separated.watching(scene, state) or relax_cell:     # a separation is looked for after every DG increment;
            batch = batch[:1]           # F-bar's last resort re-equilibrates alone with the cells' own volume change
        (files.fem / remesh_batch.STOP_FILE).unlink(missing_ok=True)
        loads = files.tables / "loads.txt"
        loads.write_text(f"{len(batch)}\n" + "".join(f"{lf!r}\n" for lf in batch))
        opts = options(seg_scene, files, dimension, seg) + extra + ["-loads", str(loads), "-inc0", str(inc0)]
        opts += predictor.options(scene, files, state, dimension)      # the last motion, across launches
        if state.reequilibrate:
            opts += ["-restart", str(files.root / seg["state"]), "-relax_steps",
                     str(state.remeshes[-1].get("relax_steps") or scene.remesh.relax_steps)]
            if relax_cell:
                opts[opts.index("-ul_volumetric") + 1] = "0"
        elif state.accepted:
            opts += ["-restart", str(files.fem / f"inc-{state.last[0]:04d}")]
        watcher = _Progress(files.fem, inc0, len(batch), batch, progress)
        failure, before, t0 = None, len(state.accepted), time.perf_counter()
        # the increments FreeFEM commits are accepted while it solves the next ones (overlap.Behind)
        behind = overlap.Behind(lambda: accept(scene, files, state, dimension), state,
                                enabled=scene.numerics.ranks < (os.cpu_count() or 1))
        try:
            with watcher, behind:
                freefem.run(entry, switches + stop_args + opts, files.fem, ranks=scene.numerics.ranks,
                            timeout=scene.numerics.timeout, log=files.root / "freefem.log")
        except freefem.NewtonFailure as exc:
            failure = exc
        finally:
            # the launch's wall time ends with FreeFEM (not after the driver's output, counted apart)
            wall = (behind.ended or time.perf_counter()) - t0
            state.post_seconds += behind.waited
            if behind.error is None:
                accept(scene, files, state, dimension)
            ended = state.last[0] if len(state.accepted) > before else None      # FreeFEM's clock at the end
            state.launches.append({"wall": wall, "increments": len(state.accepted) - before, "complete": failure is None,
                                   **summary.launch_end(files.fem, ended, failure and failure.record)})
        stopped = bool(stop_args) and remesh_batch.settle(scene, files, state, dimension, inc0, progress)
        failure = None if stopped else failure
        if state.reequilibrate and state.accepted and state.last[0] >= state.segments[-1]["first"]:
            _reequilibrated(files, state, progress)     # (the launch may go on past the re-equilibration)
        if failure is None and len(state.accepted) - before < len(batch) and not stopped:
            if _disk_full(files.root):
                raise DiskFull(files.root)
            raise freefem.FreeFemError(f"FreeFEM ended without committing increment {state.last[0] + 1} whole "
                                       f"(see {files.fem / f'inc-{state.last[0] + 1:04d}'})")
        if failure is not None:
            cut_step(scene, files, state, failure, progress, dimension)
            _save_checkpoint(files, scene, state, dimension)
            continue
        if until is not None and until(state):         # e.g. a cut at its steady state (wendel.cutting.fe_stop)
            state.pending.clear()
        if scene.loading.adaptive and not was_reequilibration:
            grow_step(scene, state, files)
        if scene.remesh and state.pending and not (was_reequilibration
                                                   and state.last[0] == state.segments[-1]["first"]):
            maybe_remesh(scene, files, state, dimension, progress)
        separated.maybe_switch(scene, files, state, dimension, progress)
        _save_checkpoint(files, scene, state, dimension)


def _reequilibrated(files: RunFiles, state: State, progress) -> None:
    """The increment on a new mesh is accepted: the remesh is complete (its report gets the residuals)."""
    state.reequilibrate = False
    rep = state.remeshes[-1]
    finish_report(rep, files.fem / f"inc-{state.segments[-1]['first']:04d}",
                  files.root / "remesh" / f"remesh-{len(state.remeshes)}.json")
    progress(f"  re-equilibrated on the new mesh: relative residual {rep['residual_after_transfer']:.2e}"
             f" -> {rep['residual_after_reequilibration']:.2e}")


def accept(scene: Scene, files: RunFiles, state: State, dimension: int) -> None:
    """Take the committed increments FreeFEM wrote: VTU, mesh quality, histories, checkpoint."""
    t0 = time.perf_counter()
    meshes: dict[str, tuple] = {}
    while state.pending:
        inc = state.last[0] + 1
        d = files.fem / f"inc-{inc:04d}"
        record = committed(d)
        if record is None:
            break
        seg = state.segment(inc)
        if seg["mesh"] not in meshes:
            points, cells = overlap.mesh_of(files.root / seg["mesh"], dimension)
            if seg["first"] == inc:
                vtu.check_node_order(files.fem / "vertices.txt", points)
            meshes[seg["mesh"]] = (points, cells)
        points, cells = meshes[seg["mesh"]]
        extra = {"reequilibration": int(state.reequilibrate and inc == seg["first"] and inc > 1)}
        if scene.problem == "mechanics":
            extra.update(judge(points, cells, vtu.read_array(d / "u.node.txt"), dimension))
            state.quality[inc] = extra
            if extra.get("inverted", 0) > 0 and scene.remesh is None:
                print(f"  warning: increment {inc}: {extra['inverted']} inverted elements in the deformed mesh "
                      f"(no [remesh] table); see summary.json warnings")
        if scene.output.vtu:
            pdata, cdata = vtu.increment_fields(d, len(points), len(cells), dimension)
            files.vtu.mkdir(exist_ok=True)
            # updated-Lagrangian: the VTU is the deformed body itself (points = current positions)
            at = vtu.current_points(pdata, points) if scene.kinematics.updated_lagrangian else points
            vtu.write_vtu(files.vtu / f"inc-{inc:04d}.vtu", at, cells, dimension, pdata, cdata)
        state.accepted.append((inc, record["load_factor"]))
        state.pending.pop(0)
        summary.append_history(files.root, separated.history_row(record, extra, seg), d / "newton.csv")
        _save_checkpoint(files, scene, state, dimension)
    if scene.output.vtu and state.accepted:
        vtu.write_pvd(files.root / "results.pvd", [(lf, f"vtu/inc-{i:04d}.vtu") for i, lf in state.accepted])
    state.post_seconds += time.perf_counter() - t0


def _new_run_dir(scene_path: Path, smoke: bool) -> Path:
    base = RESULTS / scene_path.stem / (time.strftime("%Y%m%d-%H%M%S") + ("-smoke" if smoke else ""))
    d, k = base, 1
    while True:                        # created here, atomically: parallel runs of a sweep get their own
        try:
            d.mkdir(parents=True)
            return d
        except FileExistsError:
            k += 1
            d = base.with_name(f"{base.name}-{k}")
