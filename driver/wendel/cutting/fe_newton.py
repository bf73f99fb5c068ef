"""Where an FE cut's Newton iterations go: steps after which the contact or friction sets changed, and those after
which they did not (``python -m wendel.cutting.fe_newton RUN [RUN ...]``; a row of ``wendel bench cutting``), and
the Newton iterations of its increments by load step (``--steps``).

Each Newton step of an increment (``fem/inc-*/newton.csv``; the failed tries' ``failed-attempts/*-newton.csv``)
solved on the sets of the iterate before it. The iterate it gives says whether those sets still hold
(``contact_entering``, ``contact_leaving``, ``friction_changes``: nodes whose contact or stick/slip set, or slip
direction, differ). Counted over the steps after the first of each increment (the first starts from the last
increment's state with the tool a step further, so its contraction says little) and without the trial iterates
that would invert a cell (their residual is 1e300): how many steps changed the sets (``set_change_share``) and
the median contraction ``|r_k| / |r_k-1|`` of the steps that changed them and of those that did not. The
semismooth Newton method converges fast once its sets hold; a cut whose steps mostly change them searches for
its sets (README "Where the step cuts come from").
"""

from __future__ import annotations

import csv
import math
import statistics
import sys
from pathlib import Path

INVERTED = 1e200      # a residual at least this large is FreeFEM's mark of a trial that would invert a cell
SETS = ("contact_entering", "contact_leaving", "friction_changes")     # newton.csv's counts of set changes


def steps(path: Path) -> list[tuple[bool, float]]:
    """(the sets changed, |r_k| / |r_k-1|) for each Newton step k >= 2 of one ``newton.csv``.

    >>> import tempfile
    >>> p = Path(tempfile.mkdtemp()) / "newton.csv"
    >>> rows = ["iteration,relative_residual,friction_changes", "0,5,0", "1,0.5,2", "2,0.4,1", "3,1e-3,0", "4,1e300,3"]
    >>> _ = p.write_text("".join(r + chr(10) for r in rows))
    >>> steps(p)          # step 1 left out (the increment's first), step 4 too (a trial that would invert a cell)
    [(True, 0.8), (False, 0.0025)]
    """
    return _steps(_read(path))


def _read(path: Path) -> list[dict]:
    with path.open() as f:
        return list(csv.DictReader(f))


def _steps(rows: list[dict]) -> list[tuple[bool, float]]:
    out = []
    for a, b in zip(rows[1:], rows[2:]):
        ra, rb = float(a["relative_residual"]), float(b["relative_residual"])
        if not (0 < ra < INVERTED and rb < INVERTED):
            continue
        changed = any(int(float(b.get(k) or 0)) > 0 for k in SETS)
        out.append((changed, rb / ra))
    return out


def newton_sets(root: Path) -> dict:
    """The run folder's Newton iterations, accepted and failed, and its steps by whether they changed the sets.

    The iterations are those newton.csv counts (its rows less the initial residual's), of the accepted increments
    (``fem/inc-*``) and of the failed tries kept in ``failed-attempts/``."""
    root = Path(root)
    accepted = sorted(root.glob("fem/inc-*/newton.csv"))
    failed = sorted(root.glob("failed-attempts/*-newton.csv"))
    iterations = {"accepted": 0, "failed": 0}
    with_c, without = [], []
    for kind, files in (("accepted", accepted), ("failed", failed)):
        for f in files:                 # each file read once: its iterations and its steps
            rows = _read(f)
            iterations[kind] += max(len(rows) - 1, 0)
            for changed, ratio in _steps(rows):
                (with_c if changed else without).append(ratio)
    n = len(with_c) + len(without)
    med = lambda xs: statistics.median(xs) if xs else math.nan
    return {"increments": len(accepted), "iterations": iterations["accepted"], "failed_tries": len(failed),
            "failed_iterations": iterations["failed"], "steps_counted": n,
            "set_change_share": len(with_c) / n if n else math.nan,
            "contraction_with_set_changes": med(with_c), "contraction_without": med(without)}


def newton_by_step(root: Path) -> list[dict]:
    """The accepted increments of a run (history.csv) by their load step, as a fraction of the largest (a step
    cut halves it), and the re-equilibrations (steps without time after a remesh) apart: how many, their mean
    Newton iterations and those per largest step.

    >>> import tempfile; d = Path(tempfile.mkdtemp())
    >>> rows = ["increment,load_factor,newton_iterations,reequilibration", "1,0.25,8,0", "2,0.375,6,0",
    ...         "3,0.5,4,0", "4,0.5,30,1", "5,0.75,10,0"]
    >>> _ = (d / "history.csv").write_text("\\n".join(rows) + "\\n")
    >>> [(r["step"], r["increments"], r["mean_iterations"], r["iterations_per_full_step"]) for r in newton_by_step(d)]
    [('1', 2, 9.0, 9.0), ('1/2', 2, 5.0, 10.0), ('re-equilibration', 1, 30.0, '')]
    """
    with open(Path(root) / "history.csv") as f:
        rows = list(csv.DictReader(f))
    last, steps = 0.0, []
    for r in rows:
        lf = float(r["load_factor"])
        steps.append((lf - last, int(r["newton_iterations"]), r.get("reequilibration") == "1"))
        last = lf
    full = max(d for d, _, re in steps if not re)
    groups: dict[int, list[int]] = {}
    for d, its, re in steps:
        key = -1 if re else round(math.log2(full / d))      # a step of full / 2^k
        groups.setdefault(key, []).append(its)
    out = []
    for k in sorted(groups, key=lambda k: (k < 0, k)):
        its = groups[k]
        mean = sum(its) / len(its)
        out.append({"step": "re-equilibration" if k < 0 else ("1" if k == 0 else f"1/{2 ** k}"),
                    "increments": len(its), "mean_iterations": round(mean, 1),
                    "iterations_per_full_step": "" if k < 0 else round(mean * 2 ** k, 1)})
    return out


def main(argv: list[str]) -> int:
    from ..bench import _table
    if not argv or argv == ["--steps"]:
        print("usage: python -m wendel.cutting.fe_newton [--steps] RUN [RUN ...]", file=sys.stderr)
        return 2
    if argv[0] == "--steps":
        print(_table([{"run": p, **r} for p in argv[1:] for r in newton_by_step(Path(p))]))
        return 0
    print(_table([{"run": p, **newton_sets(Path(p))} for p in argv]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
