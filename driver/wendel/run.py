"""Run a scene: build the mesh, step the load, cut steps that fail, write results, report.

:func:`run` is the table of contents; each step is a small function below it.
"""

from __future__ import annotations

import json
import os
import shutil
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from . import freefem, output, petsc, remeshing, report
from .blocks import BLOCKS, PROBLEMS
from .meshes import LABELS, build as build_mesh
from .schema import ANALYTIC_REFERENCES, BODY_FORCES, Scene
from .scene import load

RESULTS = freefem.ROOT / "results"


class StepCutError(RuntimeError):
    """An increment failed after every allowed step cut; accepted increments are on disk."""


@dataclass
class RunFiles:
    """The folders and files of one run."""

    root: Path

    @property
    def fem(self) -> Path:
        return self.root / "fem"

    @property
    def tables(self) -> Path:
        return self.root / "tables"

    @property
    def vtu(self) -> Path:
        return self.root / "vtu"

    @property
    def mesh(self) -> Path:
        return self.root / "mesh.msh"

    @property
    def checkpoint(self) -> Path:
        return self.root / "checkpoint.json"


@dataclass
class State:
    """Where the run stands: accepted increments (number, load factor) and what is left to do."""

    accepted: list[tuple[int, float]] = field(default_factory=list)
    pending: list[float] = field(default_factory=list)
    cuts: int = 0
    # meshes of the run: from increment `first` on, mesh file, base displacement and pre-strain files
    segments: list[dict] = field(default_factory=lambda: [{"first": 1, "mesh": "mesh.msh", "ubase": None, "eps0": None}])
    remeshes: list[dict] = field(default_factory=list)
    reequilibrate: bool = False
    quality: dict = field(default_factory=dict)
    step: float | None = None        # adaptive loading: the current load-factor step
    launches: list[dict] = field(default_factory=list)
    mesh_seconds: float = 0.0
    post_seconds: float = 0.0

    @property
    def last(self) -> tuple[int, float]:
        return self.accepted[-1] if self.accepted else (0, 0.0)

    def segment(self, inc: int) -> dict:
        """The mesh segment increment ``inc`` belongs to."""
        return [s for s in self.segments if s["first"] <= inc][-1]


def run(scene_path: str | Path, smoke: bool = False, ranks: int | None = None, out: Path | None = None,
        resume: Path | None = None, progress=print, png: bool | None = None, scale: float | None = None) -> Path:
    """Run the scene file ``scene_path``; return the run folder (results/<scene>/<run-id>/).

    ``ranks`` and ``png`` override numerics.ranks and output.png; ``scale`` multiplies
    geometry.h and the size of a refined zone (geometry.refine.h); ``resume`` continues the run folder
    given from its last checkpoint.
    """
    if resume is not None:
        files, scene, state = _resume(Path(resume).resolve())
        progress(f"resuming {files.root} after increment {state.last[0]} (load factor {state.last[1]:g})")
        return _execute(scene, files, state, progress)
    scene_path = Path(scene_path)
    scene = load(scene_path, smoke=smoke)
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


def run_scene(scene: Scene, scene_path: Path, out: Path, smoke: bool = False, progress=print) -> Path:
    """Run an already validated scene (read from ``scene_path``) into the folder ``out``."""
    files = RunFiles(Path(out).resolve())      # FreeFEM runs inside the run folder: paths must be absolute
    if files.root.is_dir() and any(files.root.iterdir()):
        # never mix a new run with the files of another (nor delete them): a new folder, or --resume
        raise ValueError(f"run folder {files.root} exists and is not empty: choose another --out, or continue "
                         f"the run in it with `wendel run --resume {files.root}`")
    files.root.mkdir(parents=True, exist_ok=True)
    report.write_provenance(files.root, Path(scene_path), scene, smoke)
    state = State(pending=scene.loading.load_factors())
    state.mesh_seconds, dimension = build(scene, files)
    _save_checkpoint(files, scene, state, dimension)
    return _execute(scene, files, state, progress)


def _execute(scene: Scene, files: RunFiles, state: State, progress) -> Path:
    """Solve the pending increments, then summary and picture."""
    dimension = json.loads(files.checkpoint.read_text())["dimension"]
    progress(f"wendel: {scene.description}")
    progress(f"  run folder {files.root}")
    try:
        if scene.remesh and state.accepted and state.pending and not state.reequilibrate:
            maybe_remesh(scene, files, state, dimension, progress)    # a run resumed before the decision
        solve(scene, files, state, dimension, progress)
    finally:
        report.write_summary(files.root, scene, state, dimension)
    if scene.output.png and state.accepted:
        t0 = time.perf_counter()
        last = files.vtu / f"inc-{state.last[0]:04d}.vtu"
        output.picture(last, files.root / "deformed.png", f"load factor {state.last[1]:g}", scene.output.warp)
        state.post_seconds += time.perf_counter() - t0
        report.write_summary(files.root, scene, state, dimension)
    return files.root


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


def solve(scene: Scene, files: RunFiles, state: State, dimension: int, progress) -> None:
    """Launch FreeFEM on the pending increments; cut failing steps; remesh when the mesh distorts.

    Without remeshing one launch runs all pending increments (start-up paid once); with remeshing each
    launch runs one increment so that the driver judges the mesh after every increment.
    """
    write_tables(scene, files, dimension)
    entry = entry_script(scene, dimension)
    while state.pending:
        inc0 = state.last[0] + 1
        if scene.loading.adaptive and not state.reequilibrate:
            plan_step(scene, state)
        one_by_one = scene.remesh is not None or scene.loading.adaptive
        batch = state.pending[:1] if one_by_one else list(state.pending)
        loads = files.tables / "loads.txt"
        loads.write_text(f"{len(batch)}\n" + "".join(f"{lf!r}\n" for lf in batch))
        seg = state.segment(inc0)
        opts = options(scene, files, dimension, seg) + ["-loads", str(loads), "-inc0", str(inc0)]
        if state.reequilibrate:
            opts += ["-restart", str(files.root / seg["state"])]
        elif state.accepted:
            opts += ["-restart", str(files.fem / f"inc-{state.last[0]:04d}")]
        watcher = _Progress(files.fem, inc0, len(batch), batch, progress)
        failure, before, t0 = None, len(state.accepted), time.perf_counter()
        try:
            with watcher:
                freefem.run(entry, opts, files.fem, ranks=scene.numerics.ranks,
                            timeout=scene.numerics.timeout, log=files.root / "freefem.log")
        except freefem.NewtonFailure as exc:
            failure = exc
        finally:
            accept(scene, files, state, dimension)
            state.launches.append({"wall": time.perf_counter() - t0, "increments": len(state.accepted) - before,
                                   "complete": failure is None})
        if failure is not None:
            cut_step(scene, files, state, failure, progress)
            _save_checkpoint(files, scene, state, dimension)
            continue
        if scene.loading.adaptive and not state.reequilibrate:
            grow_step(scene, state, files)
        if state.reequilibrate:
            state.reequilibrate = False
            rep = state.remeshes[-1]
            remeshing.finish_report(rep, files.fem / f"inc-{state.last[0]:04d}",
                                    files.root / "remesh" / f"remesh-{len(state.remeshes)}.json")
            progress(f"  re-equilibrated on the new mesh: relative residual {rep['residual_after_transfer']:.2e}"
                     f" -> {rep['residual_after_reequilibration']:.2e}")
        elif scene.remesh and state.pending:
            maybe_remesh(scene, files, state, dimension, progress)
        _save_checkpoint(files, scene, state, dimension)


def plan_step(scene: Scene, state: State) -> None:
    """Adaptive loading: put the next load factor (last + step, never past the next target) first."""
    loading = scene.loading
    if state.step is None:
        state.step = loading.nominal_step()
    target, last = state.pending[0], state.last[1]
    direction = 1.0 if target >= last else -1.0
    nxt = last + direction * state.step
    if (nxt - target) * direction < -1e-12 * max(1.0, abs(target)):
        state.pending.insert(0, nxt)


def grow_step(scene: Scene, state: State, files: RunFiles) -> None:
    """Adaptive loading: after an easy increment the step grows (up to loading.max_step)."""
    loading = scene.loading
    rec = json.loads((files.fem / f"inc-{state.last[0]:04d}" / "record.json").read_text())
    if rec["newton_iterations"] <= loading.easy_iterations:
        state.step = min(state.step * loading.grow, loading.max_step or loading.nominal_step())


def maybe_remesh(scene: Scene, files: RunFiles, state: State, dimension: int, progress) -> None:
    """Remesh after the last accepted increment when its deformed mesh is too poor (or asked)."""
    r = scene.remesh
    inc, lf = state.last
    if state.segments[-1]["first"] > inc:
        return      # already remeshed after this increment (a resumed run)
    q = state.quality.get(inc, {})
    poor = q.get("min_quality", 1.0) < r.min_quality or q.get("inverted", 0) > 0
    if not (poor or inc in r.at):
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
    ubase_old = output.read_array(files.root / seg["ubase"]) if seg["ubase"] else None
    progress(f"  increment {inc}: min quality {q.get('min_quality', float('nan')):.3g}"
             f"{' (asked by remesh.at)' if not poor else ''}: remeshing")
    rep = remeshing.remesh_state(files.fem / f"inc-{inc:04d}", files.root / seg["mesh"], ubase_old, dimension,
                                 files.root / mesh_new, files.root / state_dir, h, r.h_min or h / 3, r.indicator,
                                 mu=scene.material.E / (2 * (1 + scene.material.nu)))
    rep.update({"remesh": k, "after_increment": inc, "load_factor": lf})
    state.remeshes.append(rep)
    state.segments.append({"first": inc + 1, "mesh": mesh_new, "ubase": f"{state_dir}/ubase.txt",
                           "eps0": f"{state_dir}/eps0.txt", "state": state_dir})
    state.pending.insert(0, lf)
    state.reequilibrate = True


def accept(scene: Scene, files: RunFiles, state: State, dimension: int) -> None:
    """Take the committed increments FreeFEM wrote: VTU, mesh quality, histories, checkpoint."""
    t0 = time.perf_counter()
    meshes: dict[str, tuple] = {}
    while state.pending:
        inc = state.last[0] + 1
        d = files.fem / f"inc-{inc:04d}"
        if not (d / "done").is_file():
            break
        record = json.loads((d / "record.json").read_text())
        seg = state.segment(inc)
        if seg["mesh"] not in meshes:
            points, cells = output.read_mesh(files.root / seg["mesh"], dimension)
            if seg["first"] == inc:
                output.check_node_order(files.fem / "vertices.txt", points)
            meshes[seg["mesh"]] = (points, cells)
        points, cells = meshes[seg["mesh"]]
        extra = {"reequilibration": int(state.reequilibrate and inc == seg["first"] and inc > 1)}
        if scene.problem == "mechanics":
            extra.update(remeshing.judge(points, cells, output.read_array(d / "u.node.txt"), dimension))
            state.quality[inc] = extra
        if scene.output.vtu:
            pdata, cdata = output.increment_fields(d, len(points), len(cells), dimension)
            files.vtu.mkdir(exist_ok=True)
            output.write_vtu(files.vtu / f"inc-{inc:04d}.vtu", points, cells, dimension, pdata, cdata)
        state.accepted.append((inc, record["load_factor"]))
        state.pending.pop(0)
        report.append_history(files.root, {**record, **extra}, d / "newton.csv")
        _save_checkpoint(files, scene, state, dimension)
    if scene.output.vtu and state.accepted:
        output.write_pvd(files.root / "results.pvd",
                         [(lf, f"vtu/inc-{i:04d}.vtu") for i, lf in state.accepted])
    state.post_seconds += time.perf_counter() - t0


def cut_step(scene: Scene, files: RunFiles, state: State, failure: freefem.NewtonFailure, progress) -> None:
    """Halve the failed increment, or stop with a clear message when no cut is left."""
    rec = failure.record
    inc = state.last[0] + 1
    failed = files.fem / f"inc-{inc:04d}"
    if failed.is_dir():
        keep = files.root / "failed-attempts"
        keep.mkdir(exist_ok=True)
        if (failed / "newton.csv").is_file():
            shutil.copyfile(failed / "newton.csv", keep / f"inc-{inc:04d}-lf-{rec['load_factor']:.6g}-newton.csv")
        shutil.rmtree(failed)
    reason = rec.get("reason", "Newton did not converge")
    lf_prev, lf_fail = state.last[1], state.pending[0]
    state.cuts += 1
    mid = lf_prev + 0.5 * (lf_fail - lf_prev)
    smallest = scene.loading.nominal_step() / 2 ** scene.loading.max_cuts
    if reason == "limit load reached" or abs(mid - lf_prev) < smallest * (1 - 1e-9):
        what = "limit load reached" if reason == "limit load reached" else \
            f"{reason}, even after {scene.loading.max_cuts} step halvings (loading.max_cuts)"
        raise StepCutError(
            f"increment {inc} (load factor {lf_prev:g} -> {lf_fail:g}): {what}; "
            f"{len(state.accepted)} accepted increments are kept in {files.root}")
    if scene.loading.adaptive:
        state.step = abs(mid - lf_prev)
        if all(abs(lf_fail - t) > 1e-12 * max(1.0, abs(t)) for t in scene.loading.load_factors()):
            state.pending.pop(0)         # an intermediate point of the adaptive loading: plan_step re-plans
    state.pending.insert(0, mid)
    progress(f"  increment {inc}: {reason} at load factor {lf_fail:g}; cutting the step to {mid:g}")


def entry_script(scene: Scene, dimension: int) -> str:
    """The entry script that includes exactly the scene's physics modules."""
    if scene.problem != "mechanics":
        return PROBLEMS[scene.problem].entry(scene, dimension)
    tags = "".join(f"-{b}" for b in scene.blocks)
    return f"solve-{dimension}d{tags}.edp"


def options(scene: Scene, files: RunFiles, dimension: int, segment: dict | None = None) -> list[str]:
    """FreeFEM options of the scene: numbers and integer ids only (and file paths the driver made)."""
    n = scene.numerics
    segment = segment or {"mesh": "mesh.msh", "ubase": None, "eps0": None}
    opts = ["-mesh", str(files.root / segment["mesh"]), "-solver", n.solver, "-solver_tol", repr(n.solver_tol),
            "-newton_tol", repr(n.newton_tol), "-newton_maxit", str(n.newton_maxit)]
    if n.solver == "petsc":
        opts += petsc.launch_options(n.petsc.pc, n.petsc.options, n.petsc.reuse)
    if scene.problem != "mechanics":
        return opts + PROBLEMS[scene.problem].options(scene, files, dimension)
    m = scene.material
    opts += ["-mat_E", repr(m.E), "-mat_nu", repr(m.nu),
             "-el_plane_stress", "1" if scene.elasticity.plane == "stress" else "0",
             "-bc", str(files.tables / "bc.txt"), "-trac", str(files.tables / "trac.txt")]
    for key in ("ubase", "eps0"):
        if segment.get(key):
            opts += [f"-{key}", str(files.root / segment[key])]
    bf = scene.body_force
    v = list(bf.value) + [0.0] * (3 - len(bf.value))
    opts += ["-body_id", str(BODY_FORCES[bf.kind]), "-body_fx", repr(v[0]), "-body_fy", repr(v[1]),
             "-body_fz", repr(v[2])]
    if scene.reference.analytic:
        opts += ["-ref_id", str(ANALYTIC_REFERENCES[scene.reference.analytic])]
    for name in scene.blocks:
        opts += BLOCKS[name].options(getattr(scene, name), scene, files)
    return opts


def write_tables(scene: Scene, files: RunFiles, dimension: int) -> None:
    """Boundary condition tables for bc.idp (labels from meshes/labels.py)."""
    files.tables.mkdir(parents=True, exist_ok=True)
    dirichlet, neumann = [], []
    for name, b in scene.boundary.items():
        lab = LABELS[name]
        for comp, val in enumerate((b.ux, b.uy, b.uz)):
            if val is not None:
                if comp == 2 and dimension == 2:
                    raise ValueError(f"boundary.{name}.uz: a 2D scene has no z component")
                dirichlet.append(f"{lab} {comp} {val!r}")
        if b.traction is not None or b.pressure is not None:
            t = list(b.traction or [0.0, 0.0]) + [0.0] * 3
            neumann.append(f"{lab} {t[0]!r} {t[1]!r} {t[2]!r} {float(b.pressure or 0.0)!r}")
    (files.tables / "bc.txt").write_text(f"{len(dirichlet)}\n" + "".join(r + "\n" for r in dirichlet))
    (files.tables / "trac.txt").write_text(f"{len(neumann)}\n" + "".join(r + "\n" for r in neumann))


def _new_run_dir(scene_path: Path, smoke: bool) -> Path:
    stamp = time.strftime("%Y%m%d-%H%M%S")
    base = RESULTS / scene_path.stem / (stamp + ("-smoke" if smoke else ""))
    d, k = base, 1
    while True:                        # created here, atomically: parallel runs of a sweep get their own
        try:
            d.mkdir(parents=True)
            return d
        except FileExistsError:
            k += 1
            d = base.with_name(f"{base.name}-{k}")


def _save_checkpoint(files: RunFiles, scene: Scene, state: State, dimension: int) -> None:
    data = {"scene": scene.model_dump(mode="json"), "dimension": dimension,
            "accepted": state.accepted, "pending": state.pending, "cuts": state.cuts,
            "segments": state.segments, "remeshes": state.remeshes, "reequilibrate": state.reequilibrate,
            "quality": {str(k): v for k, v in state.quality.items()}, "step": state.step,
            "launches": state.launches, "mesh_seconds": state.mesh_seconds, "post_seconds": state.post_seconds}
    tmp = files.checkpoint.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=1))
    os.replace(tmp, files.checkpoint)


def _resume(root: Path) -> tuple[RunFiles, Scene, State]:
    files = RunFiles(root)
    if not files.checkpoint.is_file():
        raise FileNotFoundError(f"{root}: no checkpoint.json to resume from")
    data = json.loads(files.checkpoint.read_text())
    scene = Scene.model_validate(data["scene"])
    state = State(accepted=[tuple(a) for a in data["accepted"]], pending=data["pending"], cuts=data["cuts"],
                  launches=data["launches"], mesh_seconds=data["mesh_seconds"], post_seconds=data["post_seconds"],
                  segments=data["segments"], remeshes=data["remeshes"], reequilibrate=data["reequilibrate"],
                  quality={int(k): v for k, v in data["quality"].items()}, step=data["step"])
    # An increment committed after the last checkpoint is taken as it is; a partial one is dropped.
    report.truncate_history(files.root, state.last[0])
    accept(scene, files, state, data["dimension"])
    nxt = files.fem / f"inc-{state.last[0] + 1:04d}"
    if nxt.is_dir():
        shutil.rmtree(nxt)
    return files, scene, state


class _Progress:
    """Prints a line per committed increment while FreeFEM runs (watches the `done` markers), and every
    ``HEARTBEAT`` seconds of a long increment its last Newton row."""

    HEARTBEAT = 10.0

    def __init__(self, fem: Path, inc0: int, count: int, loads: list[float], progress):
        self.fem, self.inc0, self.count, self.loads, self.progress = fem, inc0, count, list(loads), progress
        self.stop = threading.Event()
        self.t0 = self.last_line = time.perf_counter()

    def __enter__(self):
        self.thread = threading.Thread(target=self._watch, daemon=True)
        self.thread.start()
        return self

    def __exit__(self, *exc):
        self.stop.set()
        self.thread.join()
        self._report()
        return False

    def _watch(self):
        while not self.stop.wait(0.5):
            self._report()
            if self.count > 0 and time.perf_counter() - self.last_line > self.HEARTBEAT:
                self._heartbeat()

    def _heartbeat(self):
        self.last_line = time.perf_counter()
        csv_path = self.fem / f"inc-{self.inc0:04d}" / "newton.csv"
        try:
            rows = csv_path.read_text().splitlines()
        except OSError:
            rows = []
        row = rows[-1].split(",") if len(rows) > 1 else None
        where = f"Newton iteration {row[2]}, relative residual {float(row[4]):.2e}" if row and len(row) > 4 \
            else "setting up"
        self.progress(f"  increment {self.inc0} (load factor {self.loads[0]:g}): {where}, "
                      f"{time.perf_counter() - self.t0:.0f} s")

    def _report(self):
        while self.count > 0:
            d = self.fem / f"inc-{self.inc0:04d}"
            if not (d / "done").is_file():
                return
            try:
                rec = json.loads((d / "record.json").read_text())
            except (OSError, ValueError):
                return
            self.progress(f"  increment {rec['increment']}: load factor {rec['load_factor']:g}, "
                          f"{rec['newton_iterations']} Newton iterations, "
                          f"{time.perf_counter() - self.t0:.1f} s")
            self.inc0 += 1
            self.count -= 1
            self.loads.pop(0)
            self.last_line = time.perf_counter()
