"""The output's cell stresses from the cells' strains by array operations (issue 20; `cellStressFromStrain` in
3D, `cellStressFromStrain2` in 2D plane and (r, z), edp/lib/mechanics.idp) against the stress expressions they
replace (`-DEXPRESSIONSTRESS=1` on every launch): a smoke run both ways, the same increments with every cell,
node and state file and every record entry to round-off."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from conftest import WORKFLOWS
from wendel import freefem
from wendel.results.vtu import read_array

# elastic P1: (r, z) with heat, (r, z), plane with contact, plane with heat (manufactured: its own energy rule),
# plane with heat, 3D with contact, 3D with heat and removal (thermo-free and thermo-constrained: their stresses or
# strains are zero to round-off)
SCENES = ["axisym-heated-cylinder", "axisym-sphere", "hertz", "thermo-mms", "heat-strip", "hertz-3d", "drilling-3d"]


def _largest_difference(a: Path, b: Path) -> tuple[float, str]:
    """The largest difference between two runs' increments, relative to the quantity's largest magnitude over
    the run (as scripts/ab-scenes.py: a record entry that is round-off in some increments, such as the thermal
    strain energy of a part cooled to a uniform temperature, is not read as a relative change)."""
    incs = sorted(p.name for p in a.glob("inc-*"))
    assert incs and incs == sorted(p.name for p in b.glob("inc-*"))
    diff: dict[str, list[float]] = {}
    scale: dict[str, float] = {}
    for inc in incs:
        ra, rb = (json.loads((d / inc / "record.json").read_text()) for d in (a, b))
        assert ra.keys() == rb.keys()
        pairs = []
        for k, v in ra.items():
            if k.startswith("time") or not isinstance(v, (int, float)):
                assert k.startswith("time") or v == rb[k], (inc, k)
                continue
            pairs.append((k, np.array([v], dtype=float), np.array([rb[k]], dtype=float)))
        files = sorted(p.name for p in (a / inc).glob("*.txt"))
        assert files and files == sorted(p.name for p in (b / inc).glob("*.txt"))
        pairs += [(f, read_array(a / inc / f), read_array(b / inc / f)) for f in files]
        for k, x, y in pairs:
            assert x.shape == y.shape, (inc, k)
            if x.size:
                diff.setdefault(k, []).append(float(np.abs(x - y).max()))
                scale[k] = max(scale.get(k, 0.0), float(np.abs(x).max()), float(np.abs(y).max()))
    return max((max(d) / max(scale[k], 1e-300), k) for k, d in diff.items())


@pytest.mark.parametrize("scene", SCENES)
def test_cell_stresses_from_strains_are_the_stress_expressions(scene, tmp_path, monkeypatch):
    from wendel.loop import run

    monkeypatch.setenv("WENDEL_PRESTART", "0")        # every launch through freefem._command below
    arrays = run(WORKFLOWS / f"{scene}.toml", smoke=True, out=tmp_path / "arrays", png=False, progress=lambda *_: None)
    command = freefem._command
    monkeypatch.setattr(freefem, "_command", lambda entry, options, *a, **k:
                        command(entry, [*options, "-DEXPRESSIONSTRESS=1"], *a, **k))
    expressions = run(WORKFLOWS / f"{scene}.toml", smoke=True, out=tmp_path / "expressions", png=False,
                      progress=lambda *_: None)
    assert "-DEXPRESSIONSTRESS=1" in (expressions / "freefem.log").read_text()
    assert "-DEXPRESSIONSTRESS=1" not in (arrays / "freefem.log").read_text()
    worst, where = _largest_difference(arrays / "fem", expressions / "fem")
    assert worst < 1e-12, (where, worst)
