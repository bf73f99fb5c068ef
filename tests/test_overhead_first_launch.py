"""Time outside the solve (issue 20): a quasi-static run's first FreeFEM launch started at its gate while
gmsh meshes (wendel.loop.first_launch); the same run as without it (WENDEL_PRESTART=0)."""

from __future__ import annotations

import json

import meshio
import numpy as np
import pytest

from conftest import WORKFLOWS


def _records(run):
    """Every increment's record.json without FreeFEM's clocks."""
    out = []
    for f in sorted((run / "fem").glob("inc-*/record.json")):
        rec = json.loads(f.read_text())
        out.append({k: v for k, v in rec.items() if not k.startswith("time_")})
    return out


@pytest.mark.parametrize("scene", ["upsetting", "hertz-3d"])
def test_first_launch_started_while_gmsh_meshes_gives_the_same_run(scene, tmp_path, monkeypatch):
    """upsetting (2D, remeshing: several launches, the first with FreeFEM's remesh stop) and hertz-3d (3D
    box): the first launch is the one started at its gate (no launch stopped unused), later launches start
    as before; records, VTU fields, history and tables are those of the run without; resume state too."""
    from wendel.loop import run

    ahead = run(WORKFLOWS / f"{scene}.toml", smoke=True, out=tmp_path / "ahead", png=False, progress=lambda *_: None)
    monkeypatch.setenv("WENDEL_PRESTART", "0")
    plain = run(WORKFLOWS / f"{scene}.toml", smoke=True, out=tmp_path / "plain", png=False, progress=lambda *_: None)
    s1, s2 = (json.loads((r / "summary.json").read_text()) for r in (ahead, plain))
    assert s1["launches"] == s2["launches"] >= 1 and s1["increments"] == s2["increments"]
    log1, log2 = ((r / "freefem.log").read_text() for r in (ahead, plain))
    assert log1.count("$ ") == s1["launches"] and log1.count("-DWITHGATE=1") == 1       # none stopped unused
    first1 = next(l for l in log1.splitlines() if l.startswith("$ "))
    first2 = next(l for l in log2.splitlines() if l.startswith("$ "))
    assert first1.replace(" -DWITHGATE=1", "").replace(str(ahead), "RUN") == first2.replace(str(plain), "RUN")
    assert "-DWITHGATE=1" not in log2
    r1, r2 = _records(ahead), _records(plain)
    assert len(r1) == len(r2) == s1["increments"]
    for a, b in zip(r1, r2):
        assert a.keys() == b.keys()
        nums = [k for k, v in a.items() if isinstance(v, (int, float))]
        np.testing.assert_allclose([a[k] for k in nums], [b[k] for k in nums], rtol=1e-9, atol=0)
    for f in sorted((ahead / "tables").iterdir()):
        if f.name != "loads.txt":          # the last launch's load factors: the same, checked by the records
            assert f.read_bytes() == (plain / "tables" / f.name).read_bytes(), f.name
    vtus = sorted((ahead / "vtu").glob("inc-*.vtu"))
    assert len(vtus) == s1["increments"]
    for f in vtus:
        m1, m2 = meshio.read(f), meshio.read(plain / "vtu" / f.name)
        np.testing.assert_array_equal(m1.points, m2.points)
        assert m1.point_data.keys() == m2.point_data.keys()
        for k in m1.point_data:
            np.testing.assert_allclose(m1.point_data[k], m2.point_data[k], rtol=1e-9, atol=1e-300)
    c1, c2 = (json.loads((r / "checkpoint.json").read_text()) for r in (ahead, plain))
    assert c1["accepted"] == c2["accepted"] and c1["pending"] == c2["pending"]


def test_a_first_launch_not_taken_is_stopped(tmp_path):
    """A run that stops before its first launch (here: an error while meshing) leaves no FreeFEM waiting
    at its gate."""
    from wendel.loop import first_launch
    from wendel.loop.checkpoint import RunFiles
    from wendel.scene import load

    files = RunFiles(tmp_path / "run")
    files.root.mkdir()
    scene = load(WORKFLOWS / "smoke.toml")
    with pytest.raises(RuntimeError):
        with first_launch.ahead(scene, files):
            started = first_launch._HELD[files.root]
            assert started.proc.poll() is None          # FreeFEM waits at its gate
            raise RuntimeError("meshing failed")
    assert started.proc.wait(timeout=10) is not None and not first_launch._HELD
