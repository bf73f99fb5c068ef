"""Newton options tried on the same states: ``python -m wendel.bench.newton_replay RUN [RUN ...] --try "ARGS" ...``.

A cut's path is chaotic (a step cut more or less moves every later increment), so a change of the Newton method
measured on whole cuts hides in their scatter. This replays the last FreeFEM launch of each run folder (its
remesh segment from its restart state, as ``wendel.bench.profile`` does) once as it is and once with each set of
FreeFEM options given by ``--try``, and prints per replay: the exit code (0: every increment accepted; 4: an
increment failed, where the loop would cut the step), the increments accepted, their Newton iterations, the
iterations of the failed one and the wall time. Not a benchmark: one replay each, on the ends of runs.

``python -m wendel.bench.newton_replay --states N RUN`` starts single steps from N accepted states of a run
instead (spread over its travel from a tenth of it, each inside a mesh segment and at a whole step's load
factor, with the extrapolated first guess the loop would give it): the next whole step (``full``), the same
without the first guess (``nopred``), two half steps (``half``), four quarter steps (``quarter``) and one double
step (``double``), and prints per variant how often all its steps converged, their mean Newton iterations and
wall time, and the wall time of two ways to cover each whole step: whole first and halved on failure (the loop's
way), or half steps first and quartered on failure.
"""

from __future__ import annotations

import argparse
import csv
import json
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from wendel import freefem
from wendel.bench.profile import last_launch, replay_command


def counts(out: Path) -> dict[str, int]:
    """Increments accepted, their Newton iterations and the failed increment's iterations of a launch folder.

    >>> import tempfile; d = Path(tempfile.mkdtemp())
    >>> for k, n in ((3, 2), (4, 7)):
    ...     (d / f"inc-000{k}").mkdir()
    ...     _ = (d / f"inc-000{k}" / "newton.csv").write_text("iteration\\n" + "0\\n" * (n + 1))
    >>> (d / "inc-0003" / "done").touch(); _ = (d / "failed.json").write_text('{"iterations": 7}')
    >>> counts(d)
    {'increments': 1, 'iterations': 2, 'failed_iterations': 7}
    """
    incs = sorted(f for f in out.glob("inc-*/newton.csv") if (f.parent / "done").is_file())
    its = sum(sum(1 for _ in csv.DictReader(f.open())) - 1 for f in incs)
    failed = out / "failed.json"
    return {"increments": len(incs), "iterations": its,
            "failed_iterations": int(json.loads(failed.read_text())["iterations"]) if failed.is_file() else 0}


def _launch(cmd: list[str], out: Path) -> dict:
    """Run a FreeFEM launch into ``out``: its exit code, :func:`counts` and wall time."""
    t0 = time.perf_counter()
    done = subprocess.run(cmd, env=freefem.environment(), capture_output=True, text=True)
    return {"exit": done.returncode, **counts(out), "wall_s": round(time.perf_counter() - t0, 2)}


def replay(words: list[str], extra: list[str], keep: Path | None = None) -> dict:
    """One replay of a launch with ``extra`` options: exit code, counts and wall time (its folder kept as ``keep``,
    which must not exist, when given: the launch's files, fdcheck.csv with ``-newton_fd_check``)."""
    with tempfile.TemporaryDirectory(prefix="wendel-newton-replay-") as tmp:
        out = keep or Path(tmp) / "fem"
        out.mkdir(parents=True)
        return _launch(replay_command(words, out, extra), out)


VARIANTS = {"full": (1,), "nopred": (1,), "half": (0.5, 1), "quarter": (0.25, 0.5, 0.75, 1), "double": (2,)}


def _set(words: list[str], name: str, value: str | None) -> list[str]:
    """The launch's words with option ``name`` set to ``value`` (or removed, value None).

    >>> _set(["F", "-a", "1", "-b", "2"], "-a", "3"), _set(["F", "-a", "1"], "-b", "2")
    (['F', '-a', '3', '-b', '2'], ['F', '-a', '1', '-b', '2'])
    >>> _set(["F", "-a", "1"], "-a", None)
    ['F']
    """
    words = list(words)
    if name in words:
        k = words.index(name)
        del words[k:k + 2]
        if value is not None:
            words[k:k] = [name, value]
    elif value is not None:
        words += [name, value]
    return words


def states(run: Path, count: int, start: float = 0.1) -> list[tuple[int, float, float, dict, float]]:
    """``count`` accepted increments of a run to start steps from: (increment, load factor, its step, its mesh
    segment, the whole step), inside a segment after its re-equilibration, at a whole step's load factor, from
    load factor ``start`` (a tenth of the travel) on."""
    ck = json.loads((run / "checkpoint.json").read_text())
    step = 1.0 / ck["scene"]["loading"]["steps"]
    lf_of = dict(map(tuple, ck["accepted"]))
    found = []
    for n, lf in map(tuple, ck["accepted"]):
        seg = [s for s in ck["segments"] if s["first"] <= n][-1]
        dlf = lf - lf_of.get(n - 1, lf)
        if n - 1 > seg["first"] and dlf > 0 and abs(lf / step - round(lf / step)) < 1e-6 and lf >= start:
            found.append((n, lf, dlf, seg, step))
    if len(found) < count:
        raise SystemExit(f"{run}: {len(found)} states to start from, not {count}")
    return [found[round(k * (len(found) - 1) / max(count - 1, 1))] for k in range(count)]


def step_from(run: Path, words: list[str], state: tuple, variant: str, out: Path) -> dict:
    """One variant's steps from one state (the run's last launch with its segment's mesh, the state as restart,
    the loads and the first guess of the variant)."""
    n, lf, dlf, seg, step = state
    out.mkdir(parents=True)
    loads = [lf + f * step for f in VARIANTS[variant]]
    (out / "loads.txt").write_text(f"{len(loads)}\n" + "".join(f"{x!r}\n" for x in loads))
    w = replay_command(words, out, [])
    for name, value in (("-mesh", run / seg["mesh"]), ("-ubase", run / seg["ubase"] if seg["ubase"] else None),
                        ("-restart", run / "fem" / f"inc-{n:04d}"), ("-inc0", n + 1), ("-loads", out / "loads.txt"),
                        ("-remesh_skip", None), ("-relax_steps", None), ("-newton_profile", None)):
        w = _set(w, name, None if value is None else str(value))
    guess = {"-predictor_du": None, "-predictor_dlf": None, "-predictor_lf": None}
    if variant != "nopred":
        from wendel.results import vtu
        u = lambda k: vtu.read_array(run / "fem" / f"inc-{k:04d}" / "u.node.txt")
        vtu.write_array(out / "predictor_du.txt", u(n) - u(n - 1))
        guess = {"-predictor_du": str(out / "predictor_du.txt"), "-predictor_dlf": repr(dlf),
                 "-predictor_lf": repr(lf)}
    for name, value in guess.items():
        w = _set(w, name, value)
    return {"state": n, "variant": variant, **_launch(w, out)}


def policies(rows: list[dict]) -> dict:
    """Wall time over the states of covering each whole step whole first (halved on failure, then quartered) or
    half first (quartered on failure), from the measured variants.

    >>> r = lambda n, v, e, w: {"state": n, "variant": v, "exit": e, "wall_s": w}
    >>> policies([r(1, "full", 0, 2.0), r(1, "half", 0, 2.0), r(1, "quarter", 0, 3.0),
    ...           r(2, "full", 4, 1.0), r(2, "half", 0, 2.5), r(2, "quarter", 0, 3.0)])
    {'whole_first_s': 5.5, 'half_first_s': 4.5}
    """
    by: dict[int, dict] = {}
    for r in rows:
        by.setdefault(r["state"], {})[r["variant"]] = r
    ok = lambda r: r["exit"] == 0
    half = lambda b: b["half"]["wall_s"] + (0 if ok(b["half"]) else b["quarter"]["wall_s"])
    whole = sum(b["full"]["wall_s"] + (0 if ok(b["full"]) else half(b)) for b in by.values())
    return {"whole_first_s": round(whole, 2), "half_first_s": round(sum(half(b) for b in by.values()), 2)}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m wendel.bench.newton_replay", description=__doc__.split("\n\n")[0])
    p.add_argument("runs", type=Path, nargs="+", help="run folders (with freefem.log)")
    p.add_argument("--try", dest="tries", action="append", default=[],
                   help="FreeFEM options to try, e.g. \"-newton_ls_memory 3\" (repeatable)")
    p.add_argument("--out", type=Path, help="keep the replays' folders as OUT/<run>-<k> (k = 0: as it ran)")
    p.add_argument("--states", type=int, help="steps from this many accepted states of each run instead")
    p.add_argument("--variants", default="full,half,quarter", help="with --states: of " + ", ".join(VARIANTS))
    a = p.parse_args(argv)
    if a.states:
        return _main_states(p, a)
    if not a.tries:
        p.error("give at least one --try \"OPTIONS\"")
    rows = []
    for run in a.runs:
        words = last_launch(run)
        for k, opts in enumerate(["", *a.tries]):
            keep = a.out / f"{run.name}-{k}" if a.out else None
            if keep and keep.exists():
                p.error(f"{keep} exists: give an empty --out")
            rows.append({"run": run.name, "options": opts or "(as it ran)", **replay(words, shlex.split(opts), keep)})
            print(f"{run.name} {rows[-1]['options']}: exit {rows[-1]['exit']}", file=sys.stderr)
    from wendel.bench import _table
    print(_table(rows))
    return 0


def _main_states(p: argparse.ArgumentParser, a: argparse.Namespace) -> int:
    from concurrent.futures import ThreadPoolExecutor
    from wendel.bench import _table
    variants = a.variants.split(",")
    if not set(variants) <= set(VARIANTS) or ("full" in variants) != ("half" in variants) or not variants:
        p.error(f"--variants: some of {', '.join(VARIANTS)} (full and half together)")
    summary = []
    for run in a.runs:
        words = last_launch(run)
        with tempfile.TemporaryDirectory(prefix="wendel-states-") as tmp:
            root = a.out / run.name if a.out else Path(tmp)
            jobs = [(st, v, root / f"{st[0]:04d}-{v}") for st in states(run, a.states) for v in variants]
            with ThreadPoolExecutor(2) as ex:        # these 2 cores: two FreeFEM launches at a time
                rows = list(ex.map(lambda j: step_from(run, words, *j), jobs))
        for v in variants:
            rs = [r for r in rows if r["variant"] == v]
            good = [r for r in rs if r["exit"] == 0]
            summary.append({"run": run.name, "variant": v, "converged": f"{len(good)} / {len(rs)}",
                            "iterations": round(sum(r["iterations"] for r in good) / max(len(good), 1), 1),
                            "failed_iterations": round(sum(r["failed_iterations"] for r in rs if r["exit"] != 0)
                                                       / max(len(rs) - len(good), 1), 1),
                            "wall_s": round(sum(r["wall_s"] for r in good) / max(len(good), 1), 2)})
        if {"full", "half", "quarter"} <= set(variants):
            summary.append({"run": run.name, "variant": "policies", **policies(rows)})
    print(_table(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
