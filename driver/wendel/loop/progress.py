"""Progress lines while FreeFEM runs: one per committed increment, a heartbeat during a long one."""

from __future__ import annotations

import json
import threading
import time
from pathlib import Path


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
