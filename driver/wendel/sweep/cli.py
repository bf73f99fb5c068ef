"""``wendel sweep SWEEP.toml [options]``, ``wendel sweep status TARGET``, ``wendel sweep collect TARGET``.

TARGET is the sweep file or its folder. Exit codes: 0 every run done, 1 some run failed (or is still
queued after --detach), 2 bad input (the message names the file, the key and the values), 130 interrupted
(the sweep resumes with the same command).
"""

from __future__ import annotations

import argparse
from pathlib import Path


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("target", nargs="+", metavar="ARG",
                   help="SWEEP.toml: run the sweep; `status TARGET`: report it; `collect TARGET`: write sweep.csv "
                   "and the plots (TARGET: the sweep file or its folder)")
    p.add_argument("--out", type=Path, help="sweep folder (default results/sweeps/<sweep file stem>)")
    p.add_argument("--executor", choices=("local", "slurm"), default="local")
    p.add_argument("--workers", type=int, help="local runs at a time (default cores / ranks per run)")
    p.add_argument("--partition", help="SLURM partition")
    p.add_argument("--time", type=int, help="SLURM time limit of one task [min]")
    p.add_argument("--mem", help="SLURM memory of one task (e.g. 2G)")
    p.add_argument("--cpus-per-run", type=int, help="SLURM CPUs of one run")
    p.add_argument("--parallelism", type=int, help="SLURM tasks at a time (array parallelism)")
    p.add_argument("--runs-per-task", type=int, help="SLURM runs of one task (forked from one warm process)")
    p.add_argument("--detach", action="store_true", help="SLURM: submit and return")
    p.add_argument("--quiet", action="store_true", help="no progress display")


def command(args) -> int:
    from . import collect, run_sweep, status

    first, rest = args.target[0], args.target[1:]
    if first in ("status", "collect"):
        if len(rest) != 1:
            raise ValueError(f"wendel sweep {first} takes one sweep file or sweep folder")
        if first == "status":
            root, counts, rows = status(Path(rest[0]), args.out)
            print(f"{root}: " + ", ".join(f"{n} {s}" for s, n in sorted(counts.items())))
            for r in rows:
                if r["status"] == "failed":
                    print(f"  failed {r['key']}: {r['message']}")
            return 0 if set(counts) <= {"done"} else 1
        path, rows = collect(Path(rest[0]), args.out)
        print(f"table written to {path} ({sum(r['status'] == 'done' for r in rows)}/{len(rows)} done)")
        return 0 if all(r["status"] == "done" for r in rows) else 1
    if rest:
        raise ValueError(f"wendel sweep takes one sweep file (or status/collect TARGET), got {' '.join(args.target)}")
    slurm = {"partition": args.partition, "time": args.time, "mem": args.mem, "cpus_per_run": args.cpus_per_run,
             "parallelism": args.parallelism, "runs_per_task": args.runs_per_task}
    try:
        rep = run_sweep(Path(first), out=args.out, executor=args.executor, workers=args.workers, slurm=slurm,
                        detach=args.detach, quiet=args.quiet)
    except KeyboardInterrupt:
        print("wendel: sweep interrupted; run the same command to resume it")
        return 130
    if args.detach and args.executor == "slurm":
        print(f"submitted; follow with `wendel sweep status {rep['root']}`, then `wendel sweep collect {rep['root']}`")
        return 0
    rows = rep["rows"]
    n_done = sum(r["status"] == "done" for r in rows)
    print(f"sweep: {n_done}/{len(rows)} done ({rep['skipped']} skipped as done), {rep['wall']:.1f} s; "
          f"table {rep['csv']}")
    for r in rows:
        if r["status"] != "done":
            print(f"  {r['status']} {r['key']}: {r['message']}")
    return 0 if n_done == len(rows) else 1
