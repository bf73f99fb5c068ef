"""The drilling process at workpiece scale: a remeshing drilling campaign (scene table ``[drilling]``).

:func:`run` is the table of contents. For each process step (the drill advances by ``(depth -
start_depth) / steps``, then dwells at the bottom):

1. **remove**: the body with the bore up to the new tip depth is built anew from the geometry
   (:mod:`wendel.meshes.drilling`: OCC boolean, graded mesh, boundaries re-tagged by geometry);
2. **chips**: the heat content ``int rho c (T - T_0) dV`` of the removed slice (between the old and the
   new bore) is integrated on the old mesh before removal (Gauss quadrature in (r, s, theta));
3. **transfer**: the displacement reached, temperature and plastic variables go over to the new mesh
   (:func:`wendel.remesh.step.remesh_state` with the removal as its ``make_mesh``, in the reference
   configuration: small strain; the temperature by a conservative projection, see
   :func:`wendel.remesh.removal.conservative_transfer`); the new mesh lies inside the old one, the report counts the new
   nodes that needed extrapolation (outside the old mesh: chords of the old curved surfaces);
4. **solve**: one FreeFEM increment of the thermo-mechanics over the step's time with the process
   loads on the new surfaces: the heat flux ``eta_w P_c`` split between bore bottom and wall
   (:class:`wendel.scene.blocks.drilling.Drilling` has the Kienzle force model), the thrust as a traction on
   the bore bottom, optional convection on the bore;
5. **write**: VTU (the series runs across every remesh), probe temperatures, bore profile, energies.

The same loop drills the axisymmetric (r, z) section (builder ``drilled-section`` with
``elasticity.plane = "axisymmetric"``): areas, volumes, the thermal energy, the chips' quadrature and the
conservative transfer carry the weight 2 pi r; a thermocouple at (x, y, z) sits at r = hypot(x, y).

After every completed step the process state is kept (:mod:`.drilling_state`): ``wendel run --resume`` goes on
with the next step.

Then the drill is withdrawn and the part cools on the last mesh (one launch, ``cooling_steps``
increments). Time runs as the load factor: ``t = lf * T_total``; the traction table holds
``thrust / A / lf`` so that the traction FreeFEM scales by ``lf`` is the thrust of the step.

Energy bookkeeping (J, every step, ``summary.json["drilling"]["energy"]``): heat put in by the flux =
change of the thermal energy of the body + heat removed with the chips - convection (and the
thermoelastic and plastic heat) + the transfer defect (the heat the transfer onto the new mesh created).
What is not modelled: the chips as bodies (their heat leaves at once), tool wear, the chisel edge's
forces, the torque as a traction (3D), frictional contact of the margins with the wall.

The module is above 300 lines on purpose: one process loop whose steps (remove, chips, transfer, solve,
write) share the state of :class:`Process`; the geometry (:mod:`wendel.meshes.drilling`), the removal
numerics (:mod:`wendel.remesh.removal`) and the outputs (:mod:`wendel.results.drilling`) live elsewhere.
"""

from __future__ import annotations

import json
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import freefem, prestart
from ..meshes import LABELS
from ..meshes import drilling as geometry
from ..remesh import mesher, quality, transfer
from ..remesh import step as remeshing
from ..remesh.removal import conservative_transfer, removed_slice_quadrature
from ..results import summary as report, vtu as output
from ..results.drilling import bore_profile, plots, write_csv
from . import drilling_state as kept, launch, overlap
from .ahead import Builder
from .checkpoint import RunFiles, State
from .lookahead import Lookahead
from .quasistatic import accept
from .steps import StepCutError


@dataclass
class Step:
    """One process step: its kind (drill, dwell), the tip depth at its end (m) and its end time (s)."""

    kind: str
    depth: float
    time: float


def plan(block) -> tuple[list[Step], list[float]]:
    """The removal steps and the end times of the cooling increments."""
    steps, t = [], 0.0
    if block.depth > block.start_depth:
        dt = block.advance_time() / block.steps
        dd = (block.depth - block.start_depth) / block.steps
        for k in range(1, block.steps + 1):
            steps.append(Step("drill", block.start_depth + k * dd, k * dt))
        t = steps[-1].time
    if block.dwell > 0:
        for k in range(1, block.dwell_steps + 1):
            steps.append(Step("dwell", block.depth, t + k * block.dwell / block.dwell_steps))
        t = steps[-1].time
    cooling = [t + k * block.cooling / block.cooling_steps for k in range(1, block.cooling_steps + 1)] \
        if block.cooling > 0 else []
    return steps, cooling


def run(scene, scene_path: Path, out: Path, smoke: bool = False, progress=print, resume: bool = False) -> Path:
    """Run the drilling scene ``scene`` into the folder ``out``; return it. ``resume``: go on from the last
    completed removal step kept in the folder (:mod:`.drilling_state`)."""
    files = RunFiles(Path(out).resolve())
    if not resume:
        if files.root.is_dir() and any(files.root.iterdir()):
            raise ValueError(f"run folder {files.root} exists and is not empty: choose another --out")
        files.root.mkdir(parents=True, exist_ok=True)
        report.write_provenance(files.root, Path(scene_path), scene, smoke)
    work = scene.model_copy(deep=True)
    if smoke and scene.smoke.steps is not None:
        work.drilling.steps = scene.smoke.steps             # smoke.steps: removal steps of a smoke run
    scene = work.model_copy(deep=True)
    block = scene.drilling
    total = block.total_time()
    work.thermal.duration = total
    if getattr(work, "plasticity", None) is not None:
        work.plasticity.load_time = total
    plain = work.model_copy(update={"drilling": None})      # the mechanics + thermal entry script
    dim = 2 if scene.geometry.builder == "drilled-section" else 3      # (r, z) section or 3D body
    entry = launch.entry_script(plain, dim)
    steps, cooling = plan(block)
    progress(f"wendel: {scene.description}")
    progress(f"  run folder {files.root}")
    progress(f"  P_c = {block.power():.1f} W (torque {block.drill_torque():.3g} N m), thrust "
             f"{block.thrust_force():.1f} N, eta_w = {block.eta_w:g}; {len(steps)} removal steps, "
             f"{len(cooling)} cooling increments, {total:.3g} s")
    state = State(pending=[])
    state.segments = []
    proc = Process(scene, work, files, state, entry, total, progress, dim)
    proc.plain, proc.steps, proc.cooling = plain, steps, cooling
    done, cooled = 0, False
    if resume:
        done, cooled = kept.restore(proc)
        progress(f"  resuming after removal step {done} of {len(steps)}{' and the cooling' if cooled else ''}")
    else:
        launch.write_tables(work, files, dim)
    try:
        for k, step in enumerate(steps, 1):
            if k > done:
                proc.removal_step(k, step)
                kept.save(proc, k, False)
        if cooling and not cooled:
            proc.cool(cooling)
            kept.save(proc, len(steps), True)
    finally:
        proc.look.join()
        prestart.abandon(proc.ahead)        # a launch started for a step that did not come
        proc.builder.close()
    summary = report.write_summary(files.root, work, state, dim)
    proc.finish(summary)
    return files.root


class Process:
    """The state of a drilling run between steps, and its records."""

    def __init__(self, scene, work, files, state, entry, total, progress, dim: int = 3):
        self.scene, self.work, self.files, self.state = scene, work, files, state
        self.dim, self.axi = dim, dim == 2          # 2: the axisymmetric (r, z) section (x = r, y = z)
        self.block, self.entry, self.total, self.progress = scene.drilling, entry, total, progress
        th = work.thermal
        self.rho_c = th.rho * th.c
        self.T0 = th.T_initial if th.T_initial is not None else th.T_ref
        self.g = scene.geometry
        self.h_bore = self.block.h_bore or self.g.h / 3
        self.rows: list[dict] = []           # one per step / cooling increment
        self.probes: list[dict] = []
        self.profiles: list[dict] = []
        self.energy_prev = 0.0               # thermal energy at the end of the last step (J)
        self.heat_boundary_prev = 0.0
        self.heat_te_prev = 0.0
        self.heat_pl_prev = 0.0
        self.depth_prev = self.block.start_depth
        self.steps, self.cooling = [], []
        self.ahead = None                    # the next launch, started while the driver prepares it (prestart)
        self.builder = Builder()             # the next removal step's mesh, built while FreeFEM solves
        self.look = Lookahead()              # and what the driver needs of it, found beside the solve
        self.mesh = None

    # ---- the geometry of the workpiece
    def body(self, depth: float) -> tuple[str, dict]:
        """The builder (``section``, ``cylinder`` or ``block``) and its arguments for the tip at ``depth``."""
        params = {k: v for k, v in self.g.params.items() if k != "h"}
        kind = "section" if self.axi else "cylinder" if self.g.builder == "drilled-cylinder" else "block"
        return kind, dict(depth=depth, diameter=self.block.diameter, point_angle=self.block.point_angle,
                          h=self.g.h, h_bore=self.h_bore, grade=self.block.grade, **params)

    def build(self, depth: float, path: Path) -> dict:
        ahead = self.look.mesh(path)             # taken and read beside the last solve (wendel.loop.lookahead)
        if ahead is not None:
            return ahead
        if not self.builder.take(path):          # not built ahead (wendel.loop.ahead): here
            kind, kwargs = self.body(depth)
            with remeshing._quiet_stdout():
                if kind == "section":
                    geometry.drilled_section(path, **kwargs)
                else:
                    geometry.drilled(path, kind, **kwargs)
        pts, _, cells, _, facets, tags = mesher.read_mesh(path)
        return {"points": pts, "cells": cells, "facets": facets, "tags": tags}

    def submit_bodies(self, k: int, n: int = 2) -> None:
        """The bodies of steps ``k`` to ``k + n - 1`` (0-based) to the mesh worker, where the tip moves (a path
        asked for already is not asked again): ahead, as a 3D body (0.5-0.9 s of gmsh here) takes longer than a
        removal step's launch."""
        for j in range(k, k + n):
            if j < len(self.steps) and self.steps[j].depth != (self.steps[j - 1].depth if j else self.depth_prev):
                kind, kwargs = self.body(self.steps[j].depth)
                self.builder.submit(kind, self.files.root / f"meshes/step-{j + 1:03d}.msh", kwargs)

    def areas(self, mesh: dict) -> dict[str, float]:
        p, f, tags = mesh["points"], mesh["facets"], mesh["tags"]
        if self.axi:        # (r, z) edges: the areas of their surfaces of revolution, 2 pi r_mid |e| (exact)
            a = 2 * np.pi * 0.5 * (p[f[:, 0], 0] + p[f[:, 1], 0]) * np.linalg.norm(p[f[:, 1]] - p[f[:, 0]], axis=1)
        else:
            a = 0.5 * np.linalg.norm(np.cross(p[f[:, 1]] - p[f[:, 0]], p[f[:, 2]] - p[f[:, 0]]), axis=1)
        return {n: float(a[tags == LABELS[n]].sum()) for n in geometry.BORE}

    # ---- one removal step
    def removal_step(self, k: int, step: Step) -> None:
        files, state = self.files, self.state
        t0 = time.perf_counter()
        mesh_rel = f"meshes/step-{k:03d}.msh"
        (files.root / "meshes").mkdir(exist_ok=True)
        row = {"step": k, "kind": step.kind, "depth": step.depth, "time": step.time,
               "dt": step.time - (self.rows[-1]["time"] if self.rows else 0.0)}
        restart = None
        if state.segments and step.depth == self.depth_prev:
            # nothing removed (a dwell): the body and its mesh stay, the state goes on as it is
            seg, mesh = state.segments[-1], self.mesh
            restart = str(files.fem / f"inc-{state.last[0]:04d}")
            row.update(chips_heat=0.0, nodes_outside_old_mesh=0, remesh_seconds=0.0, transfer_seconds=0.0,
                       chips_seconds=0.0)
        elif not state.segments:
            self.submit_bodies(k)              # the worker starts on the next bodies while the driver meshes this one
            mesh = self.build(step.depth, files.root / mesh_rel)
            seg = {"first": k, "mesh": mesh_rel, "ubase": None, "eps0": None}
            row.update(chips_heat=0.0, energy_after_transfer=0.0, nodes_outside_old_mesh=0,
                       remesh_seconds=time.perf_counter() - t0, transfer_seconds=0.0, chips_seconds=0.0)
        else:
            old_seg = state.segments[-1]
            old_inc = files.fem / f"inc-{state.last[0]:04d}"
            old_mesh = self.mesh
            tc = time.perf_counter()
            chips, outside = self.chips_heat(old_mesh, output.read_array(old_inc / "T.node.txt"),
                                             self.depth_prev, step.depth)
            row["chips_seconds"] = time.perf_counter() - tc
            built = {}

            def make_mesh(xd, mesh_old, mesh_new, h, size_indicator=None, h_min=None):
                built["mesh"] = self.build(step.depth, Path(mesh_new))
                q = self.look.quality(Path(mesh_new)) or quality.mesh_quality(built["mesh"]["points"],
                                                                               built["mesh"]["cells"])
                pts = built["mesh"]["points"][:, :self.dim]
                return {"min_sicn": q["min"],
                        "measure_old": float(remeshing.cell_volumes(xd, old_mesh["cells"], self.axi).sum()),
                        "measure_new": float(remeshing.cell_volumes(pts, built["mesh"]["cells"], self.axi).sum())}

            state_rel = f"remesh/state-{k:03d}"
            ubase_old = output.read_array(files.root / old_seg["ubase"]) if old_seg["ubase"] else None
            rep = remeshing.remesh_state(old_inc, files.root / old_seg["mesh"], ubase_old, self.dim,
                                         files.root / mesh_rel, files.root / state_rel, self.g.h, self.h_bore, "",
                                         axisymmetric=self.axi, make_mesh=make_mesh, deformed=False)
            mesh = built["mesh"]
            rep["remesh_seconds"] += self.look.unbooked()      # waited for after the launch (wendel.loop.lookahead)
            if self.block.transfer == "conservative":
                self.conserve_heat(old_mesh, old_inc, mesh, files.root / state_rel, rep)
            # Small strain on nested bodies: the displacement reached is the state (its strain is compatible on
            # the new mesh); remesh_state's pre-strain eps0 (for a remesh of the deformed body) is not used,
            # its cell-node-cell recovery would leave incompatible strains, i.e. spurious residual stresses.
            shutil.copyfile(files.root / state_rel / "ubase.txt", files.root / state_rel / "u.node.txt")
            seg = {"first": k, "mesh": mesh_rel, "ubase": None, "eps0": None, "state": state_rel}
            rep.update({"step": k, "depth_old": self.depth_prev, "depth_new": step.depth, "chips_heat": chips,
                        "chips_points_outside": outside})
            (files.root / "remesh").mkdir(exist_ok=True)
            (files.root / "remesh" / f"remesh-{k:03d}.json").write_text(json.dumps(rep, indent=1))
            state.remeshes.append(rep)
            t_new = output.read_array(files.root / state_rel / "therm_T.node.txt")
            row.update(chips_heat=chips, energy_after_transfer=self.energy(mesh, t_new),
                       nodes_outside_old_mesh=rep["nodes_outside_old_mesh"], new_nodes=rep["new_nodes"],
                       remesh_seconds=rep["remesh_seconds"], transfer_seconds=rep["transfer_seconds"])
        if restart is None:
            state.segments.append(seg)
            restart = seg.get("state")
        self.mesh = mesh
        row["mesh_nodes"] = len(mesh["points"])
        row["removed_volume"] = geometry.bore_volume(step.depth, self.block.diameter / 2, self.block.point_angle)
        areas = self.areas(mesh)
        wall_share = self.block.wall_fraction if areas["bore_wall"] > 0 else 0.0
        q_in = self.block.eta_w * self.block.power()
        fluxes = {"bore_wall": wall_share * q_in / areas["bore_wall"] if areas["bore_wall"] > 0 else 0.0,
                  "bore_bottom": (1 - wall_share) * q_in / areas["bore_bottom"] if areas["bore_bottom"] > 0 else 0.0}
        row["heat_in"] = row["dt"] * sum(fluxes[n] * areas[n] for n in fluxes)
        row.update({f"area_{n}": a for n, a in areas.items()})
        traction = -self.block.thrust_force() / areas["bore_bottom"] if areas["bore_bottom"] > 0 else 0.0
        self.launch(k, [step.time], seg, fluxes, traction, restart=restart)
        row["launch_seconds"] = self.state.launches[-1]["wall"]
        self.depth_prev = step.depth
        self.close_rows([row])

    def conserve_heat(self, old_mesh: dict, old_inc: Path, mesh: dict, state_dir: Path, rep: dict) -> None:
        """Replace the interpolated temperature by its lumped L2 projection (keeps the heat the body holds)."""
        t0 = time.perf_counter()
        T_old = output.read_array(old_inc / "therm_T.node.txt")
        rep["energy_interpolated"] = self.energy(mesh, output.read_array(state_dir / "therm_T.node.txt"))
        T_new, _ = conservative_transfer(old_mesh["points"], old_mesh["cells"], T_old, mesh["points"], mesh["cells"],
                                         axisymmetric=self.axi)
        output.write_array(state_dir / "therm_T.node.txt", T_new)
        if output.read_array(state_dir / "therm_T.qp.txt").size == len(mesh["cells"]):     # P1: one point per cell
            output.write_array(state_dir / "therm_T.qp.txt", transfer.nodes_to_cells(mesh["cells"], T_new))
        rep["max_T_after"] = float(T_new.max())
        rep["transfer_seconds"] += time.perf_counter() - t0

    def cool(self, times: list[float]) -> None:
        """The drill is withdrawn: no flux, no thrust; the part cools on the last mesh."""
        k = self.state.last[0] + 1
        seg = self.state.segments[-1]
        rows = [{"step": k + i, "kind": "cool", "depth": self.depth_prev, "time": t,
                 "dt": t - (self.rows[-1]["time"] if i == 0 else times[i - 1]), "chips_heat": 0.0, "heat_in": 0.0,
                 "nodes_outside_old_mesh": 0, "mesh_nodes": len(self.mesh["points"])} for i, t in enumerate(times)]
        self.launch(k, times, seg, {"bore_wall": 0.0, "bore_bottom": 0.0}, 0.0,
                    restart=str(self.files.fem / f"inc-{self.state.last[0]:04d}"))
        self.close_rows(rows)

    # ---- FreeFEM
    def launch(self, inc0: int, times: list[float], seg: dict, fluxes: dict, traction: float, restart) -> None:
        files, work, state = self.files, self.work, self.state
        lfs = [t / self.total for t in times]
        opts = launch.options(work, files, self.dim, seg)       # writes the scene's thermal table: replaced below
        rows = [(LABELS[n], *b.row()) for n, b in work.thermal.boundary.items()]
        for n, q in fluxes.items():
            if q:
                rows.append((LABELS[n], 1, q, 0.0))
            if self.block.bore_h > 0:
                rows.append((LABELS[n], 2, self.block.bore_h, self.block.bore_T_inf))
        (files.tables / "thermal_bc.txt").write_text(
            f"{len(rows)}\n" + "".join(f"{lab} {kind} {a!r} {b!r}\n" for lab, kind, a, b in rows))
        trac = [line for line in (files.tables / "trac.txt").read_text().splitlines()[1:] if line.strip()]
        trac = [r for r in trac if int(r.split()[0]) != LABELS["bore_bottom"]]
        if traction and len(lfs) == 1:      # axial: z in 3D, y = z in (r, z)
            t = [0.0, 0.0, 0.0]
            t[self.dim - 1] = traction / lfs[0]
            trac.append(f"{LABELS['bore_bottom']} {t[0]!r} {t[1]!r} {t[2]!r} 0.0")
        (files.tables / "trac.txt").write_text(f"{len(trac)}\n" + "".join(r + "\n" for r in trac))
        loads = files.tables / "loads.txt"
        loads.write_text(f"{len(lfs)}\n" + "".join(f"{lf!r}\n" for lf in lfs))
        scene_opts, opts = opts, self.command(inc0, seg, restart, opts)
        state.pending = list(lfs)
        ahead, self.ahead = self.ahead, None
        taken, wall = ahead is not None and ahead.options == opts, None
        k = inc0 + len(lfs) - 1                  # the step after this launch's last: its body while FreeFEM solves
        self.submit_bodies(k)
        self.look.start(self, k)        # beside the solve: the point sets of this mesh, the next mesh
        # the transfer's scipy (0.5 s) and the plots' imports (0.4-0.6 s) while FreeFEM solves, not before the
        # first launch or at the first remesh and the end
        overlap.preload("scipy.spatial", "scipy.sparse")
        if self.scene.output.png:       # and a first figure drawn (fonts, text, log labels: wendel.results.plotwarm)
            overlap.preload("matplotlib", "matplotlib.pyplot", "wendel.results.plotwarm")
        before, t0 = len(state.accepted), time.perf_counter()
        try:
            # the next launch starts beside this solve at nice 19 (its start takes only the CPU the solve leaves;
            # at nice 0 it slowed the solve on this shared machine: drilling-3d 10.8 -> 12.0 s), and is given the
            # driver's priority at its "go"; where the priority cannot be raised again, it starts after this
            # launch, while the driver accepts, removes and transfers (wendel.prestart)
            def early():
                self.ahead = self.start_next(inc0 + len(lfs), seg, scene_opts, early=True)

            freefem.run(self.entry, opts, files.fem, ranks=work.numerics.ranks, timeout=work.numerics.timeout,
                        log=files.root / "freefem.log", started=ahead, beside=early)
            wall = time.perf_counter() - t0      # FreeFEM's end: the accept below is driver output (no double count)
            if self.ahead is None:
                self.ahead = self.start_next(inc0 + len(lfs), seg, scene_opts)
        finally:
            accept(work, files, state, self.dim)
            state.launches.append({"wall": wall if wall is not None else time.perf_counter() - t0,
                                   "increments": len(state.accepted) - before, "complete": not state.pending,
                                   "prestarted": taken})
        if state.pending:
            raise StepCutError(f"increment {state.last[0] + 1} of the drilling run was not accepted; "
                                      f"see {files.root / 'freefem.log'}")

    def command(self, inc0: int, seg: dict, restart, opts: list[str] | None = None) -> list[str]:
        """The FreeFEM options of a launch (``opts``: :func:`wendel.loop.launch.options` of ``seg``)."""
        files = self.files
        opts = launch.options(self.work, files, self.dim, seg) if opts is None else opts
        opts = launch.macros(self.plain, self.dim) + ["-DWITHSTRESSFIELDS=1"] + opts + \
            ["-loads", str(files.tables / "loads.txt"), "-inc0", str(inc0)]
        return opts + (["-restart", str(files.root / restart)] if restart else [])

    def start_next(self, inc: int, seg: dict, scene_opts: list[str], early: bool = False):
        """Start the launch of increment ``inc`` (the next removal step or the cooling) while the driver accepts
        this one, removes and transfers (:mod:`wendel.prestart`), with the options :meth:`removal_step` or
        :meth:`cool` will ask for if nothing but the mesh, the restart and ``-inc0`` change (``scene_opts``:
        this launch's :func:`wendel.loop.launch.options`, not computed again: that writes tables); else None.
        A launch asked otherwise is not taken. ``early``: beside this launch's solve (:func:`wendel.prestart.start`)."""
        k = inc - 1                                     # the step (or cooling) just launched: increment k
        if k < len(self.steps):                         # the next removal step
            step, now = self.steps[k], self.steps[k - 1] if k >= 1 else None
            if now is not None and step.depth == now.depth:      # a dwell: same body, from the increment
                nxt, restart = seg, str(self.files.fem / f"inc-{k:04d}")
            else:
                nxt = {"first": inc, "mesh": f"meshes/step-{inc:03d}.msh", "ubase": None, "eps0": None,
                       "state": f"remesh/state-{inc:03d}"}
                restart = nxt["state"]
        elif k == len(self.steps) and self.cooling:     # the cooling on the last mesh
            nxt, restart = seg, str(self.files.fem / f"inc-{k:04d}")
        else:
            return None
        opts = list(scene_opts)
        opts[opts.index("-mesh") + 1] = str(self.files.root / nxt["mesh"])
        return prestart.start(self.entry, self.command(inc, nxt, restart, opts), self.files.fem,
                              ranks=self.work.numerics.ranks, log=self.files.root / "freefem.log", early=early)

    # ---- bookkeeping after a launch
    def close_rows(self, rows: list[dict]) -> None:
        self.look.join()
        first = self.state.last[0] - len(rows) + 1
        for i, row in enumerate(rows):
            inc = first + i
            d = self.files.fem / f"inc-{inc:04d}"
            rec = json.loads((d / "record.json").read_text())
            T = output.read_array(d / "T.node.txt")
            energy = self.energy(self.mesh, T)
            start = row.get("energy_after_transfer", self.energy_prev) if i == 0 else self.energy_prev
            row["increment"] = inc
            row["energy"] = energy
            row["energy_change"] = energy - start
            row["transfer_defect"] = (start - (self.energy_prev - row["chips_heat"])) if i == 0 else 0.0
            row["heat_boundary"] = rec["heat_boundary"] - self.heat_boundary_prev
            row["convection"] = row["heat_boundary"] - row["heat_in"]
            row["heat_thermoelastic"] = rec["heat_thermoelastic"] - self.heat_te_prev
            row["heat_plastic"] = rec["heat_plastic"] - self.heat_pl_prev
            row["freefem_energy_change"] = rec["thermal_energy_change"]
            row["max_temperature"] = rec["max_temperature"]
            self.heat_boundary_prev, self.heat_te_prev = rec["heat_boundary"], rec["heat_thermoelastic"]
            self.heat_pl_prev = rec["heat_plastic"]
            self.energy_prev = energy
            self.rows.append(row)
            self.record_probes(inc, row, T)
            self.record_profile(inc, row, d)
            self.progress(f"  step {row['step']} ({row['kind']}): depth {row['depth'] * 1e3:.3g} mm, t = {row['time']:.3g} s, "
                          f"T_max {rec['max_temperature']:.1f} K, chips {row['chips_heat']:.3g} J, "
                          f"{row.get('nodes_outside_old_mesh', 0)} nodes extrapolated")

    def energy(self, mesh: dict, T: np.ndarray) -> float:
        """Thermal energy of the body, int rho c (T - T_0) dV (J), exact for the P1 field (in (r, z):
        2 pi int r (T - T_0) dA, with int_K r v = |K| / 12 (sum r_i sum v_i + sum r_i v_i) for P1 r and v)."""
        cells = mesh["cells"]
        if self.axi:
            area = remeshing.cell_volumes(mesh["points"][:, :2], cells)
            r, v = mesh["points"][cells, 0], (T - self.T0)[cells]
            return float(self.rho_c * 2 * np.pi * area @ ((r.sum(1) * v.sum(1) + (r * v).sum(1)) / 12))
        vol = remeshing.cell_volumes(mesh["points"], cells)
        return float(self.rho_c * vol @ transfer.nodes_to_cells(cells, T - self.T0))

    def chips_heat(self, mesh: dict, T: np.ndarray, d0: float, d1: float) -> tuple[float, int]:
        """Heat content int rho c (T - T_0) dV of the slice the drill removes from d0 to d1 (J), on the old mesh."""
        pts, w = self.slice_quadrature(d0, d1)
        if len(pts) == 0:
            return 0.0, 0
        vals, outside = transfer.transfer_nodal(mesh["points"], mesh["cells"], T - self.T0, pts)
        return float(self.rho_c * w @ vals), int(outside)

    def slice_quadrature(self, d0: float, d1: float) -> tuple[np.ndarray, np.ndarray]:
        """Points and weights of :meth:`chips_heat`'s rule (in (r, z): the columns r and z)."""
        pts, w = removed_slice_quadrature(d0, d1, self.block.diameter / 2, self.block.point_angle,
                                          self.g.params.get("height", 0.03), self.axis, n_theta=1 if self.axi else 48)
        return (pts[:, [0, 2]] if self.axi else pts), w          # (r, 0, z) -> (r, z)

    @property
    def axis(self) -> tuple[float, float]:
        return (0.0, 0.0) if self.axi else tuple(self.g.params.get("axis", (0.0, 0.0)))

    def record_probes(self, inc: int, row: dict, T: np.ndarray) -> None:
        if not self.block.probes:
            return
        names = [p.name for p in self.block.probes]
        pos = self.probe_positions()
        inside = transfer.locate(self.mesh["points"], self.mesh["cells"], pos)[0] >= 0
        vals, _ = transfer.transfer_nodal(self.mesh["points"], self.mesh["cells"], T, pos)
        self.probes.append({"time": row["time"], **{n: float(v) if ok else float("nan")
                                                     for n, v, ok in zip(names, vals, inside)}})

    def probe_positions(self) -> np.ndarray:
        pos = np.array([p.position for p in self.block.probes], dtype=float)
        if self.axi:        # a thermocouple at (x, y, z) sits at r = hypot(x, y) of the section
            pos = np.column_stack([np.hypot(pos[:, 0], pos[:, 1]), pos[:, 2]])
        return pos

    def record_profile(self, inc: int, row: dict, d: Path) -> None:
        """Bore diameter error 2 u_r along the depth, and the stresses of the cells at the wall."""
        prof = bore_profile(self.mesh, d, self.axis, self.g.params.get("height", 0.03), self.block.bore_bins, self.dim)
        if prof is not None:
            self.profiles.append({"increment": inc, "time": row["time"], "kind": row["kind"], **prof})

    # ---- summary, tables, pictures
    def finish(self, summary: dict) -> None:
        root = self.files.root
        tables = root / "tables"
        write_csv(tables / "drilling-steps.csv", self.rows)
        if self.probes:
            write_csv(tables / "probes.csv", self.probes)
        rows = self.rows
        heat_in = sum(r["heat_in"] for r in rows)
        chips = sum(r["chips_heat"] for r in rows)
        conv = sum(r["convection"] for r in rows)
        te = sum(r["heat_thermoelastic"] for r in rows)
        plastic = sum(r["heat_plastic"] for r in rows)
        defect = sum(r["transfer_defect"] for r in rows)
        d_energy = rows[-1]["energy"] if rows else 0.0
        mismatch = heat_in + conv + te + plastic - d_energy - chips
        scale = max(abs(heat_in), 1e-300)
        shares = [(r.get("remesh_seconds", 0) + r.get("transfer_seconds", 0) + r.get("chips_seconds", 0))
                  / max(r.get("remesh_seconds", 0) + r.get("transfer_seconds", 0) + r.get("chips_seconds", 0)
                        + r.get("launch_seconds", 1e-300), 1e-300) for r in rows if r["kind"] != "cool"]
        b = self.block
        out = {
            "process": {"power": b.power(), "torque": b.drill_torque(), "thrust": b.thrust_force(), "eta_w": b.eta_w,
                        "wall_fraction": b.wall_fraction, "time_total": self.total,
                        "removal_steps": sum(r["kind"] != "cool" for r in rows),
                        "cooling_increments": sum(r["kind"] == "cool" for r in rows)},
            "energy": {"heat_in": heat_in, "thermal_energy_change": d_energy, "chips_heat": chips,
                       "convection": conv, "thermoelastic": te, "plastic_heat": plastic, "transfer_defect": defect,
                       "balance_mismatch": mismatch, "balance_error": abs(mismatch) / scale},
            "remesh": {"nodes_extrapolated": [r.get("nodes_outside_old_mesh", 0) for r in rows if r["kind"] != "cool"],
                       "new_nodes": [r.get("new_nodes", r["mesh_nodes"]) for r in rows if r["kind"] != "cool"],
                       "remesh_transfer_share": shares, "meshes_built_ahead": self.builder.taken,
                       "launches_started_ahead": sum(bool(l.get("prestarted")) for l in self.state.launches),
                       "lookahead_seconds": self.look.seconds, "lookahead_wait": self.look.waited,
                       "meshes_read_beside": self.look.taken,
                       "mean_remesh_transfer_share": float(np.mean(shares)) if shares else 0.0,
                       "step_seconds": [r.get("remesh_seconds", 0) + r.get("transfer_seconds", 0)
                                        + r.get("chips_seconds", 0) + r.get("launch_seconds", 0)
                                        for r in rows if r["kind"] != "cool"]},
            "probes_peak": {n: float(np.nanmax([p[n] for p in self.probes])) for n in (p.name for p in b.probes)} if self.probes else {},
        }
        if self.profiles:
            last = self.profiles[-1]
            drilled = [p for p in self.profiles if p["kind"] != "cool"]
            out["bore"] = {"depth": last["depth"], "diameter_error_after": last["diameter_error"],
                           "diameter_error_end_of_drilling": drilled[-1]["diameter_error"] if drilled else [],
                           "hoop_stress_after": last["hoop_stress"], "axial_stress_after": last["axial_stress"]}
        summary["drilling"] = out
        summary["outputs"] = campaign_outputs(out, self.profiles)
        (root / "summary.json").write_text(json.dumps(summary, indent=1))
        (root / "drilling.json").write_text(json.dumps({**out, "steps": rows, "profiles": self.profiles}, indent=1))
        if self.scene.output.png:
            plots(root, rows, self.probes, self.profiles)
        # the ledger as the README states it: what came in = where it went (conv and te are gains, so losses negative)
        plastic_in = f" + plastic {plastic:.4g} J" if plastic else ""
        self.progress(f"  heat in {heat_in:.4g} J{plastic_in} = stored {d_energy:.4g} + chips {chips:.4g}"
                      f" + convected out {-conv:.4g} + thermoelastic {-te:.3g}; mismatch {abs(mismatch) / scale:.2e}"
                      f" (transfer defect {defect:.3g} J)")
        pics = [n for n in ("probes.png", "bore.png", "energy.png") if (root / n).is_file()]
        if pics:
            self.progress(f"  pictures: {', '.join(str(root / n) for n in pics)}")
        if self.probes:
            self.progress(f"  probe histories (thermocouples): {tables / 'probes.csv'}")
        self.progress(f"  per step: {tables / 'drilling-steps.csv'}; all steps and bore profiles: {root / 'drilling.json'}")




def campaign_outputs(out: dict, profiles: list[dict]) -> dict:
    """Scalars of a drilling run for a campaign's table (``wendel sweep`` reads summary.json["outputs"]): the peak
    temperature of each thermocouple (K), the bore diameter error 2 u_r (m; mean over the depth bins and largest
    magnitude) at the end of drilling and at the end of the run (after cooling), and the energy balance error."""
    res = {f"peak_T_{name}": v for name, v in out.get("probes_peak", {}).items()}
    drilled = [p for p in profiles if p["kind"] != "cool"]
    for label, prof in (("end_of_drilling", drilled[-1] if drilled else None),
                        ("after_cooling", profiles[-1] if profiles else None)):
        if prof is None:
            continue
        d = np.array(prof["diameter_error"], dtype=float)
        if np.isfinite(d).any():
            res[f"bore_diameter_error_{label}"] = float(np.nanmean(d))
            res[f"bore_diameter_error_max_{label}"] = float(d[np.nanargmax(np.abs(d))])
    res["energy_balance_error"] = out["energy"]["balance_error"]
    return res
