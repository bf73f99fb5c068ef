"""Where a launch's seconds go, hook by hook: ``python -m wendel.bench.profile RUN [--pairs N] [--base "ARGS"]``.

Replays the last FreeFEM launch of a run folder (the last command of RUN/freefem.log, with this tree's entry
script, into a scratch folder, ``-newton_profile 1``) and prints the seconds and calls of each hook of the
Newton loop of edp/lib/mechanics.idp (profile.csv: the constitutive trial, the internal forces, the thermal
residual, the tangent matrix, the kinematics' tangent terms, the contact and friction constraints, the linear
solve, ...) with their share of the launch. Only the last launch replays as it ran: the run's tables
(loads.txt, predictor_du.txt) are those of its last launch. With ``--base "ARGS"`` each of N pairs runs the
launch once with ARGS added (say ``"-plast_compiled 0"``) and once as it is, alternating, and the table gives the
medians of both and their ratio.
"""

from __future__ import annotations

import argparse
import csv
import shlex
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from wendel import freefem


def last_launch(run: Path) -> list[str]:
    """The FreeFEM command of a run's last launch, as its freefem.log has it (without the setpriv prefix)."""
    log = run / "freefem.log"
    if not log.is_file():
        raise SystemExit(f"{run}: no freefem.log (not a run folder)")
    lines = [ln[2:] for ln in log.read_text(errors="replace").splitlines() if ln.startswith("$ ")]
    if not lines:
        raise SystemExit(f"{log}: no launch command in it")
    words = shlex.split(lines[-1])
    if words[:3] == ["setpriv", "--pdeathsig", "TERM"]:
        words = words[3:]
    return words


def replay_command(words: list[str], out: Path, extra: list[str]) -> list[str]:
    """The launch with this tree's entry script, its output into ``out`` and the profile on.

    >>> replay_command(["FreeFem++-mpi", "-nw", "/old/edp/mechanics.edp", "-out", "/r/fem", "-inc0", "3"],
    ...                Path("/tmp/p"), ["-plast_compiled", "0"])[3:]
    ['-out', '/tmp/p', '-inc0', '3', '-newton_profile', '1', '-plast_compiled', '0']
    """
    words = list(words)
    scripts = [k for k, w in enumerate(words) if w.endswith(".edp")]
    if not scripts or "-out" not in words:
        raise SystemExit("the launch command has no .edp entry script or no -out")
    words[scripts[0]] = str(freefem.EDP / Path(words[scripts[0]]).name)
    words[words.index("-out") + 1] = str(out)
    return [*words, "-newton_profile", "1", *extra]


def profile_once(words: list[str], extra: list[str]) -> dict[str, tuple[float, int]]:
    """One replay: {hook: (seconds, calls)}, with ``launch_wall`` the launch's own wall time."""
    with tempfile.TemporaryDirectory(prefix="wendel-profile-") as tmp:
        out = Path(tmp) / "fem"
        out.mkdir()
        cmd = replay_command(words, out, extra)
        done = subprocess.run(cmd, env=freefem.environment(), capture_output=True, text=True)
        prof = out / "profile.csv"
        if not prof.is_file():
            tail = "\n".join((done.stdout + done.stderr).strip().splitlines()[-8:])
            raise SystemExit(f"the replay wrote no profile.csv (no increment accepted; exit {done.returncode}):"
                             f"\n{tail}")
        return {r["hook"]: (float(r["seconds"]), int(r["calls"])) for r in csv.DictReader(prof.open())}


def table(runs: list[dict[str, tuple[float, int]]], base: list[dict[str, tuple[float, int]]]) -> str:
    """Medians per hook (and against the base's, when there is one), the hooks that took time."""
    wall = statistics.median(r["launch_wall"][0] for r in runs)
    rows = []
    hooks = [h for h in runs[0] if h != "launch_wall"]
    # the median seconds of a hook over replays; "other": the launch outside every hook
    seconds = lambda rs, h: statistics.median(r["launch_wall"][0] - sum(r[k][0] for k in hooks) if h == "other"
                                              else r[h][0] for r in rs)
    for h in [*hooks, "other", "launch_wall"]:
        calls = 1 if h == "other" else runs[0][h][1]
        s = seconds(runs, h)
        if h not in ("other", "launch_wall") and s < 1e-3 * wall:
            continue
        row = {"hook": h, "calls": calls, "seconds": f"{s:.3f}", "ms a call": f"{1e3 * s / max(calls, 1):.2f}",
               "share": f"{100 * s / wall:.1f} %"}
        if base:
            b = seconds(base, h)
            row["base seconds"] = f"{b:.3f}"
            row["ratio"] = f"{s / b:.2f}" if b > 0 else "-"
        rows.append(row)
    from wendel.bench import _table
    return _table(rows)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m wendel.bench.profile", description=__doc__.split("\n\n")[0])
    p.add_argument("run", type=Path, help="a run folder (with freefem.log)")
    p.add_argument("--pairs", type=int, default=1, help="replays (with --base: pairs, alternating)")
    p.add_argument("--base", default="", help="FreeFEM options of the base replays, e.g. \"-plast_compiled 0\"")
    a = p.parse_args(argv)
    if a.pairs < 1:
        p.error("--pairs must be at least 1")
    words = last_launch(a.run)
    base_extra = shlex.split(a.base)
    runs, base = [], []
    for k in range(a.pairs):
        if base_extra:
            base.append(profile_once(words, base_extra))
        runs.append(profile_once(words, []))
        print(f"replay {k + 1} of {a.pairs}: launch {runs[-1]['launch_wall'][0]:.2f} s"
              + (f", base {base[-1]['launch_wall'][0]:.2f} s" if base else ""), file=sys.stderr)
    print(table(runs, base))
    return 0


if __name__ == "__main__":
    sys.exit(main())
