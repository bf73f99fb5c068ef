"""Newton options tried on the same states: ``python -m wendel.bench.newton_replay RUN [RUN ...] --try "ARGS" ...``.

A cut's path is chaotic (a step cut more or less moves every later increment), so a change of the Newton method
measured on whole cuts hides in their scatter. This replays the last FreeFEM launch of each run folder (its
remesh segment from its restart state, as ``wendel.bench.profile`` does) once as it is and once with each set of
FreeFEM options given by ``--try``, and prints per replay: the exit code (0: every increment accepted; 4: an
increment failed, where the loop would cut the step), the increments accepted, their Newton iterations, the
iterations of the failed one and the wall time. Not a benchmark: one replay each, on the ends of runs.
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
    ...     (d / f"inc-000{k}").mkdir(); _ = (d / f"inc-000{k}" / "newton.csv").write_text("iteration\\n" + "0\\n" * (n + 1))
    >>> (d / "inc-0003" / "done").touch(); _ = (d / "failed.json").write_text('{"iterations": 7}')
    >>> counts(d)
    {'increments': 1, 'iterations': 2, 'failed_iterations': 7}
    """
    incs = sorted(f for f in out.glob("inc-*/newton.csv") if (f.parent / "done").is_file())
    its = sum(sum(1 for _ in csv.DictReader(f.open())) - 1 for f in incs)
    failed = out / "failed.json"
    return {"increments": len(incs), "iterations": its,
            "failed_iterations": int(json.loads(failed.read_text())["iterations"]) if failed.is_file() else 0}


def replay(words: list[str], extra: list[str], keep: Path | None = None) -> dict:
    """One replay of a launch with ``extra`` options: exit code, counts and wall time (its folder kept as ``keep``,
    which must not exist, when given: the launch's files, fdcheck.csv with ``-newton_fd_check``)."""
    with tempfile.TemporaryDirectory(prefix="wendel-newton-replay-") as tmp:
        out = keep or Path(tmp) / "fem"
        out.mkdir(parents=True)
        t0 = time.perf_counter()
        done = subprocess.run(replay_command(words, out, extra), env=freefem.environment(), capture_output=True,
                              text=True)
        return {"exit": done.returncode, **counts(out), "wall_s": f"{time.perf_counter() - t0:.1f}"}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m wendel.bench.newton_replay", description=__doc__.split("\n\n")[0])
    p.add_argument("runs", type=Path, nargs="+", help="run folders (with freefem.log)")
    p.add_argument("--try", dest="tries", action="append", default=[],
                   help="FreeFEM options to try, e.g. \"-newton_ls_memory 3\" (repeatable)")
    p.add_argument("--out", type=Path, help="keep the replays' folders as OUT/<run>-<k> (k = 0: as it ran)")
    a = p.parse_args(argv)
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


if __name__ == "__main__":
    sys.exit(main())
