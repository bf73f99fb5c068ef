"""The steady-state measures of an FE cut (wendel.cutting.fe_steady) on made-up force histories."""

from __future__ import annotations

import numpy as np

from wendel.cutting.fe_steady import steady

H = 150e-6


def _history(travel_um: float, level, every: int = 7, step: float = 2.5e-6):
    """Increments of ``step`` with a re-equilibration row after every ``every``; ``level(x, cycle)``: F_c."""
    rows, x, k = [], 0.0, 0
    while x < travel_um * 1e-6 - 1e-12:
        for _ in range(every):
            x += step
            f = level(x, k)
            rows.append({"tool_travel_m": x, "Fc_N": f, "Ft_N": 0.5 * f, "chip_thickness_m": 3e-4})
        rows.append({"tool_travel_m": x, "Fc_N": 0.8 * f, "Ft_N": 0.4 * f, "chip_thickness_m": 3e-4})
        k += 1
    return rows


def test_remesh_scatter_passes_the_filter_but_not_the_cycles():
    # cycle means alternating +-4 % (a remesh-to-remesh scatter): the cycle measure sees 8 %, the means over
    # one h (8.6 cycles of 17.5 um) stay within 2 % of each other
    st = steady(_history(1200, lambda x, k: 500.0 * (1.04 if k % 2 else 0.96)), H)
    assert st["cycles"] is None and st["last_window_spreads"]["cycles"]["Fc_N"] > 0.07
    assert st["filtered"] is not None and st["filtered"]["spreads"]["Fc_N"] <= 0.02
    assert abs(st["filtered"]["values"]["Fc_N"] / 500.0 - 1) < 0.01 and st["filtered_window_m"] == 2 * H


def test_a_drift_fails_every_measure():
    # 3 % per h: over the filter's window of 2 h the means differ by about 6 %
    st = steady(_history(1200, lambda x, k: 500.0 * (1 + 0.03 * x / H)), H)
    assert st["filtered"] is None and st["cycles"] is None
    assert 0.04 < st["last_window_spreads"]["filtered"]["Fc_N"] < 0.08


def test_a_settled_cut_is_found_by_all_after_its_rise():
    st = steady(_history(1200, lambda x, k: 500.0 * min(1.0, 0.5 + x / 600e-6)), H)
    for m in ("cycles", "filtered"):
        assert st[m] is not None and st[m]["start_m"] >= 300e-6 - 2 * H
        assert abs(st[m]["values"]["Fc_N"] - 500.0) < 1.0


def test_a_cut_shorter_than_the_windows_reports_none():
    st = steady(_history(100, lambda x, k: 500.0), H)          # 100 um: less than one h of travel
    assert st["filtered"] is None and st["cycles"] is None
    assert st["last_window_spreads"]["filtered"] == {"Fc_N": None, "Ft_N": None, "chip_thickness_m": None}
