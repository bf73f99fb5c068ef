"""End a cut at its steady state (``cutting.stop_when_steady``).

A cut long enough to settle spends its last stretch confirming what was already found (session 26: the 2.4 mm r/2
F-bar cut's steady window closed at 2,089 um, 36.4 of its 40.2 minutes). With ``cutting.stop_when_steady`` the
quasi-static loop asks :class:`SteadyStop` after every launch that ended well (a launch is a remesh cycle: the
increments from one remesh to the next) whether the remesh-cycle means of F_c, F_t and the chip thickness have
stayed within ``cutting.steady_tol`` over ``cutting.steady_length`` of travel (the ``cycles`` measure of
:mod:`wendel.cutting.fe_steady`, the one the report gives first; ``cutting.steady_measure = "filtered"``: its running
means over that length within the tolerance over twice it, the dynamometer's view that a remesh-to-remesh scatter of
F_t does not hide, as on the titanium cut). If so the loop drops the increments left and
the run ends as a completed run; ``steady-stop.json`` in the run folder says where and why, and the report copies
it into ``cutting.json`` (``stopped_at_steady``). The cut is the same as without the stop up to there: the
check only reads the accepted increments (their VTU, once each: an increment's row is kept by the VTU's
identity, so an increment the loop forgot and solved again is read again).
"""

from __future__ import annotations

import csv
import json
import math
import time
from pathlib import Path

import numpy as np

from .fe import MM

FILE = "steady-stop.json"


class SteadyStop:
    """The loop's stop rule for the cut of ``scene`` (a validated cutting scene) in the run folder ``root``."""

    def __init__(self, root: Path, scene, progress=print):
        c = scene.cutting
        self.root, self.progress, self.width = Path(root), progress, c.width
        self.h, self.rake = c.uncut_thickness * MM, math.radians(c.rake)
        self.length, self.tol, self.measure = length(scene), c.steady_tol, c.steady_measure
        from .fe_run import tool_start
        self.tip0 = np.array(tool_start(scene)["tip"])
        self.rows: dict[int, tuple] = {}         # increment -> (VTU identity, row)
        self.seconds = 0.0                       # the checks' own time (also in the run's driver output phase)

    def __call__(self, state) -> bool:
        """True when the cut has reached its steady state (and ``steady-stop.json`` is written)."""
        from .fe_steady import _detect, cycle_means, running_means
        t0 = time.perf_counter()
        rows = self._rows()
        if not rows:
            found = None
        elif self.measure == "filtered":         # the running means over one length, within tol over two
            found = _detect(running_means(rows, self.length), 2 * self.length, self.tol)
        else:
            found = _detect(cycle_means(rows), self.length, self.tol)
        self.seconds += time.perf_counter() - t0
        if found:
            last = rows[-1]
            stop = {"increment": int(last["increment"]), "tool_travel_m": last["tool_travel_m"],
                    "window": found, "measure": self.measure, "length_m": self.length, "tol": self.tol,
                    "increments_left": len(state.pending), "check_seconds": self.seconds}
            (self.root / FILE).write_text(json.dumps(stop, indent=1))
            v = found["values"]
            what = "running means" if self.measure == "filtered" else "cycle means"
            self.progress(f"  steady from {found['start_m'] * 1e6:.0f} to {found['end_m'] * 1e6:.0f} um of travel "
                          f"({what} within {self.tol:.0%}): F_c {v['Fc_N']:.4g} N, F_t {v['Ft_N']:.4g} N, "
                          f"chip {v['chip_thickness_m'] * 1e6:.4g} um; the cut ends at "
                          f"{last['tool_travel_m'] * 1e6:.0f} um (cutting.stop_when_steady)")
        state.post_seconds += time.perf_counter() - t0
        return bool(found)

    def _rows(self) -> list[dict]:
        """F_c, F_t, chip thickness and travel of every accepted increment so far (cutting.csv's)."""
        import meshio

        from .fe_run import measured
        out = []
        with (self.root / "history.csv").open() as f:
            history = list(csv.DictReader(f))
        for rec in history:
            inc = int(rec["increment"])
            path = self.root / "vtu" / f"inc-{inc:04d}.vtu"
            try:
                st = path.stat()
            except FileNotFoundError:
                continue
            key = (st.st_mtime_ns, st.st_size)
            if self.rows.get(inc, (None,))[0] != key:
                shift, got, fc, ft = measured(rec, meshio.read(path), self.tip0, self.rake, self.h, self.width)
                self.rows[inc] = (key, {"increment": inc, "tool_travel_m": -shift[0] / MM, "Fc_N": fc, "Ft_N": ft,
                                        "chip_thickness_m": got["chip_thickness"] / MM})
            out.append(self.rows[inc][1])
        return out


def length(scene) -> float:
    """The travel [m] over which the cut's steady state is judged: ``cutting.steady_length``, else one h."""
    c = scene.cutting
    return c.steady_length if c.steady_length is not None else c.uncut_thickness


def rule(root: Path, scene, progress=print) -> SteadyStop | None:
    """The stop rule of a cut whose scene asks for it (``cutting.stop_when_steady``), else None."""
    return SteadyStop(root, scene, progress) if scene.cutting.stop_when_steady else None
