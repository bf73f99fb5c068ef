"""Provenance, histories and summary.json of a run.

summary.json holds the fingerprints of the last increment (DoFs, Newton iterations, errors, physical
quantities) and the wall time by phase: mesh (gmsh), FreeFEM start-up (launch wall time minus
FreeFEM's own clock), assembly, linear solve, constitutive update, FreeFEM output, driver
post-processing (VTU, histories, checkpoints) on the critical path, remeshing and transfer, picture.
"""

from __future__ import annotations

import csv
import json
import os
import platform
import shutil
import socket
import subprocess
import sys
import threading
import time
from importlib import metadata
from pathlib import Path

from .. import __version__

ROOT = Path(__file__).resolve().parents[3]


def _git_commit() -> str:
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True, timeout=5)
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=5).stdout.strip()
        return out.stdout.strip() + ("+dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def _freefem_version() -> str:
    try:
        out = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "freefem++"], capture_output=True, text=True, timeout=5)
        return out.stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def write_provenance(root: Path, scene_path: Path, scene, smoke: bool, record: dict | None = None) -> None:
    """The scene as run and where it ran: commit, versions, command line, host, start time; ``record``: more JSON
    files (name: data) beside scene.toml (the FE cut's cutting scene as run: wendel.cutting.fe_run.report_resumed).

    The commit and the package versions (two git and one dpkg-query process, seven package metadata parsed:
    0.17 s, a seventh of a smoke run, issue 20) are looked up in a thread while the run meshes and solves;
    provenance.json is written at once without them (a resumed run needs its ``smoke``), then again with
    them. :func:`write_summary` waits for the thread (:func:`provenance_done`)."""
    # first and atomically: a run stopped before its first checkpoint restarts from it (wendel run --resume)
    _write_json(root / "scene.resolved.json", scene.model_dump(mode="json"))
    shutil.copyfile(scene_path, root / "scene.toml")
    for name, data in (record or {}).items():
        _write_json(root / name, data)
    prov = {"command": sys.argv, "smoke": smoke, "host": socket.gethostname(), "platform": platform.platform(),
            "cpus": os.cpu_count(), "start": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
    _write_json(root / "provenance.json", prov)

    def lookup() -> None:
        versions = {"wendel": __version__, "python": sys.version.split()[0], "freefem++": _freefem_version()}
        for pkg in ("gmsh", "meshio", "numpy", "scipy", "pydantic", "pyvista", "matplotlib"):
            try:
                versions[pkg] = metadata.version(pkg)
            except metadata.PackageNotFoundError:
                versions[pkg] = "missing"
        _write_json(root / "provenance.json", {"git_commit": _git_commit(), "versions": versions, **prov})

    thread = threading.Thread(target=lookup, name="wendel-provenance", daemon=True)
    _LOOKUPS[root.resolve()] = thread
    thread.start()


_LOOKUPS: dict[Path, threading.Thread] = {}
"""The provenance look-up of each run folder still running (:func:`write_provenance`)."""


def provenance_done(root: Path) -> None:
    """Wait until the run's provenance.json holds the commit and the versions."""
    thread = _LOOKUPS.pop(root.resolve(), None)
    if thread is not None:
        thread.join()


def _write_json(path: Path, data: dict) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data, indent=1))
    os.replace(tmp, path)


def append_history(root: Path, record: dict, newton_csv: Path) -> None:
    """One row per accepted increment in history.csv; its Newton rows appended to newton.csv."""
    hist = root / "history.csv"
    keys = [k for k, v in record.items() if isinstance(v, (int, float))]
    new = not hist.exists() or hist.stat().st_size == 0   # created empty by a run stopped in this instant
    if not new:      # the columns of the first row (a run that changes its modules, loop/separated.py, keeps them)
        with open(hist, newline="") as f:
            keys = next(csv.reader(f), keys)
    with open(hist, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, extrasaction="ignore")
        if new:
            w.writeheader()
        w.writerow(record)
    rows = newton_csv.read_text().splitlines() if newton_csv.is_file() else []
    all_newton = root / "newton.csv"
    if rows:
        header = not all_newton.exists() or all_newton.stat().st_size == 0
        with open(all_newton, "a") as f:
            f.write("\n".join(rows if header else rows[1:]) + "\n")


def truncate_history(root: Path, last_increment: int) -> None:
    """Drop history and Newton rows past ``last_increment`` (a resumed run writes them again)."""
    for name in ("history.csv", "newton.csv"):
        path = root / name
        if not path.is_file():
            continue
        lines = path.read_text().splitlines()
        if not lines or not lines[0].startswith("increment,"):
            # created but stopped before its header was written: the next accepted increment writes it
            path.unlink()
            continue
        width = len(lines[0].split(","))
        # a row cut short by a crash or a full disk has fewer fields than the header: dropped
        keep = lines[:1] + [l for l in lines[1:] if len(l.split(",")) == width
                            and int(float(l.split(",", 1)[0])) <= last_increment]
        tmp = path.with_suffix(".tmp")
        tmp.write_text("\n".join(keep) + "\n")
        os.replace(tmp, path)


def read_records(root: Path) -> list[dict]:
    """record.json of every accepted increment, in order."""
    return [json.loads((d / "record.json").read_text())
            for d in sorted((root / "fem").glob("inc-*")) if (d / "done").is_file()]


def launch_end(fem: Path, last: int | None, failed: dict | None) -> dict:
    """``{"freefem_end": FreeFEM's own clock when a launch ended}`` for :func:`launch_phases`: at a failed
    increment its failed.json's ``time_total`` (``failed``), otherwise that of the launch's last committed
    increment ``last`` (read before a roll back drops increments); ``{}`` when neither is known. The time between
    the last kept increment and this end counts as failed increments, not as start-up.

    >>> launch_end(Path("."), None, {"time_total": 7.5}), launch_end(Path("."), None, None)
    ({'freefem_end': 7.5}, {})
    """
    try:
        if failed is not None:
            return {"freefem_end": float(failed["time_total"])}
        if last is not None:
            record = json.loads((fem / f"inc-{last:04d}" / "record.json").read_text())
            return {"freefem_end": float(record["time_total"])}
    except (OSError, ValueError, KeyError, TypeError):
        pass
    return {}


def launch_phases(launches: list[dict], records: list[dict]) -> dict:
    """Wall time by phase of FreeFEM's launches from their wall times (the driver's) and FreeFEM's clocks,
    cumulative within a launch (so the last record of each launch counts). Start-up (and exit) is a launch's
    wall time less FreeFEM's clock at its end; that end is ``freefem_end`` when the launch recorded one (a
    failed increment's failed.json, or increments rolled back after it), and the time from the last kept
    increment to it is ``failed_increments`` (the Newton work of an increment whose step was then cut: it was
    counted as start-up before, 2.95 of 5.4 s on the 300 um cut of "Newton on the cut"). A launch that kept
    no increment is ``failed_launches`` whole.

    >>> rec = {"time_total": 5.0, "time_assembly": 2.0, "time_solve": 1.0, "time_constitutive": 1.0, "time_output": 0.5}
    >>> ph = launch_phases([{"wall": 8.5, "increments": 1, "freefem_end": 8.0}, {"wall": 1.0, "increments": 0}], [rec])
    >>> ph["freefem_startup"], ph["failed_increments"], ph["freefem_other"], ph["failed_launches"]
    (0.5, 3.0, 0.5, 1.0)
    >>> launch_phases([{"wall": 8.5, "increments": 1}], [rec])["freefem_startup"]     # an older checkpoint
    3.5
    """
    phases = {"freefem_startup": 0.0, "assembly": 0.0, "linear_solve": 0.0, "constitutive": 0.0,
              "freefem_output": 0.0, "freefem_other": 0.0, "failed_increments": 0.0}
    by_launch, idx = [], 0
    for launch in launches:
        n = launch["increments"]
        chunk = records[idx: idx + n] if n else []
        idx += len(chunk)
        by_launch.append((launch, chunk[-1] if chunk else None))
    for launch, rec in by_launch:
        if rec is None:
            continue
        inner = rec["time_total"]
        end = max(launch.get("freefem_end", inner), inner)
        phases["freefem_startup"] += max(launch["wall"] - end, 0.0)
        phases["failed_increments"] += end - inner
        phases["assembly"] += rec["time_assembly"]
        phases["linear_solve"] += rec["time_solve"]
        phases["constitutive"] += rec["time_constitutive"]
        phases["freefem_output"] += rec["time_output"]
        phases["freefem_other"] += inner - rec["time_assembly"] - rec["time_solve"] - rec["time_constitutive"] - rec["time_output"]
    phases["failed_launches"] = sum(l["wall"] for l, r in by_launch if r is None)
    return phases


def write_summary(root: Path, scene, state, dimension: int, picture: float | None = None) -> dict:
    """summary.json: fingerprints of the last increment and wall time by phase (``picture``: the seconds
    the run waited for deformed.png, its own phase)."""
    records = read_records(root)
    ph = launch_phases(state.launches, records)
    phases = {"mesh": state.mesh_seconds, **{k: ph[k] for k in ("freefem_startup", "assembly", "linear_solve",
              "constitutive", "freefem_output", "freefem_other", "failed_increments")},
              "driver_output": state.post_seconds, "failed_launches": ph["failed_launches"]}
    # remeshing and field transfer between launches (issue 20: they were in no phase)
    phases["remesh"] = sum(r.get("remesh_seconds", 0.0) + r.get("transfer_seconds", 0.0)
                           for r in getattr(state, "remeshes", []) if isinstance(r, dict))
    if picture is not None:
        phases["picture"] = picture
    total = sum(phases.values())
    last = records[-1] if records else {}
    summary = {
        "scene": scene.description,
        "dimension": dimension,
        "blocks": scene.blocks,
        "increments": len(state.accepted),
        "pending_increments": len(state.pending),
        "completed": not state.pending,
        "step_cuts": state.cuts,
        "launches": len(state.launches),
        "newton_iterations": sum(r["newton_iterations"] for r in records),
        "dofs": last.get("dofs"),
        "elements": last.get("elements"),
        "ranks": last.get("ranks"),
        "solver": last.get("solver"),
        "wall_time": total,
        "wall_time_by_phase": phases,
        # VTU, histories and checkpoints of increments written while FreeFEM solved the next ones (in no phase)
        "driver_output_behind": getattr(state, "behind_seconds", 0.0),
        "share_startup_and_io": (phases["freefem_startup"] + phases["freefem_output"] + phases["driver_output"]
                                 + phases.get("picture", 0.0)) / total
        if total else None,
        "remeshes": state.remeshes,
        "errors": _errors(last),
        "warnings": warnings(state, scene),
        "last_increment": last,
    }
    from ..meshes.cache import sidecar

    if sidecar(root / "mesh.msh").is_file():      # the mesh came from (or went into) WENDEL_MESH_CACHE
        summary["mesh_cache"] = json.loads(sidecar(root / "mesh.msh").read_text())
    if (root / "stopped.json").is_file():
        summary["stopped"] = json.loads((root / "stopped.json").read_text())
    prov_path = root / "provenance.json"
    provenance_done(root)
    if prov_path.is_file():
        prov = json.loads(prov_path.read_text())
        prov["end"] = time.strftime("%Y-%m-%dT%H:%M:%S%z")
        _write_json(prov_path, prov)
    _write_json(root / "summary.json", summary)
    return summary


def warnings(state, scene) -> list[str]:
    """Silent trouble: a DG penalty below its stability bound; inverted elements in a deformed mesh that was
    not remeshed."""
    from ..scene.blocks.discretization import penalty_warnings

    dg = getattr(scene, "discretization", None)
    dim = 3 if scene.geometry.builder == "box" or scene.geometry.dimension == 3 else 2
    low = penalty_warnings(dg, dim) if dg is not None else []
    inverted = sorted(inc for inc, q in state.quality.items() if q.get("inverted", 0) > 0)
    if not inverted:
        return low
    what = "no [remesh] table" if scene.remesh is None else "remeshing did not remove them"
    return low + [f"increments {', '.join(map(str, inverted))}: the deformed mesh has inverted elements ({what}); "
            f"results there are not trustworthy"]


def _errors(last: dict) -> dict:
    """The errors of the last increment: closed-form ones as computed (relative where the module makes them
    so), the analytic L2 and H1 errors also relative to the reference field's norms.

    >>> _errors({"error_l2": 0.5, "reference_l2": 2.0, "error_h1": -1, "error_p0": 0.01})
    {'error_l2': 0.5, 'error_p0': 0.01, 'error_l2_relative': 0.25}
    """
    out = {k: v for k, v in last.items() if k.startswith("error_") and isinstance(v, (int, float)) and v >= 0}
    for norm in ("l2", "h1"):
        ref = last.get(f"reference_{norm}", -1)
        if f"error_{norm}" in out and isinstance(ref, (int, float)) and ref > 0:
            out[f"error_{norm}_relative"] = out[f"error_{norm}"] / ref
    return out
