"""The opt-in mesh cache (WENDEL_MESH_CACHE, wendel.meshes.cache) with the real gmsh: a cached mesh is the
fresh build byte for byte and a run's results do not change with a cold or a warm cache; a changed h misses;
a corrupt entry is rebuilt, never used; two processes building one key at once leave one valid entry;
without the variable no cache folder appears."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

from conftest import WORKFLOWS
from wendel.meshes import build
from wendel.meshes.cache import ENV

BOX = {"x": (0.0, 1.0), "y": (0.0, 0.5), "z": (0.0, 0.5), "h": 0.2}    # m: a few hundred tetrahedra


def _entries(root: Path) -> list[Path]:
    return sorted(root.iterdir())


def test_cached_mesh_is_the_fresh_build_and_a_changed_h_misses(tmp_path, monkeypatch):
    monkeypatch.delenv(ENV, raising=False)
    cache = tmp_path / "cache"
    fresh = build("box", tmp_path / "fresh.msh", **BOX)
    assert fresh.cache is None and not cache.exists()          # without the variable: no cache, no folder
    monkeypatch.setenv(ENV, str(cache))
    cold = build("box", tmp_path / "cold.msh", **BOX)
    warm = build("box", tmp_path / "warm.msh", **BOX)
    assert cold.cache["hit"] is False and warm.cache["hit"] is True and cold.cache["key"] == warm.cache["key"]
    data = (tmp_path / "fresh.msh").read_bytes()
    assert (tmp_path / "cold.msh").read_bytes() == data == (tmp_path / "warm.msh").read_bytes()
    for f in ("dimension", "boundaries", "nodes", "elements"):
        assert getattr(warm, f) == getattr(fresh, f), f
    assert warm.path == tmp_path / "warm.msh"
    finer = build("box", tmp_path / "finer.msh", **{**BOX, "h": 0.15})
    assert finer.cache["hit"] is False and finer.cache["key"] != cold.cache["key"]
    assert finer.elements > fresh.elements
    assert [p.name for p in _entries(cache)] == sorted([cold.cache["key"], finer.cache["key"]])


def test_a_corrupt_entry_is_rebuilt_not_used(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    monkeypatch.setenv(ENV, str(cache))
    first = build("rectangle", tmp_path / "a.msh", h=0.25)
    entry = cache / first.cache["key"]
    good = (entry / "mesh.msh").read_bytes()
    (entry / "mesh.msh").write_bytes(good.replace(b"$Nodes", b"$Nodes\n", 1))     # one byte more
    with pytest.warns(RuntimeWarning, match="corrupt entry"):
        again = build("rectangle", tmp_path / "b.msh", h=0.25)
    assert again.cache["hit"] is False
    assert (tmp_path / "b.msh").read_bytes() == good == (entry / "mesh.msh").read_bytes()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert build("rectangle", tmp_path / "c.msh", h=0.25).cache["hit"] is True
    assert _entries(cache) == [entry]


def test_two_processes_building_one_key_leave_one_valid_entry(tmp_path):
    cache = tmp_path / "cache"
    code = ("import sys; from wendel.meshes import build; "
            "b = build('box', sys.argv[1], x=(0, 1), y=(0, 1), z=(0, 1), h=0.12); print(b.cache['hit'], b.elements)")
    env = {**os.environ, ENV: str(cache)}
    procs = [subprocess.Popen([sys.executable, "-c", code, str(tmp_path / f"{i}.msh")], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for i in range(2)]
    outs = [p.communicate(timeout=120) for p in procs]
    assert all(p.returncode == 0 for p in procs), outs
    entries = _entries(cache)
    assert len(entries) == 1 and not entries[0].name.startswith("."), entries    # no temporary folder left
    meta = json.loads((entries[0] / "meta.json").read_text())
    data = (entries[0] / "mesh.msh").read_bytes()
    assert hashlib.sha256(data).hexdigest() == meta["sha256"]
    assert (tmp_path / "0.msh").read_bytes() == data == (tmp_path / "1.msh").read_bytes()
    assert {o.split()[1] for o, _ in outs} == {str(meta["elements"])}


def _fingerprint(run: Path) -> dict:
    """The results of a run without its clocks: summary counts, the history but its time_* columns, and every
    field of every VTU file."""
    import csv

    import meshio

    s = json.loads((run / "summary.json").read_text())
    rows = [{k: v for k, v in r.items() if not k.startswith("time_")} for r in csv.DictReader((run / "history.csv").open())]
    fields = {f.name: {k: v.tolist() for k, v in meshio.read(f).point_data.items()}
              for f in sorted((run / "vtu").glob("*.vtu"))}
    return {"counts": [s[k] for k in ("increments", "completed", "newton_iterations", "dofs", "elements")],
            "history": rows, "fields": fields, "mesh": (run / "mesh.msh").read_bytes()}


def test_a_run_gives_the_same_results_with_a_cold_and_a_warm_cache(tmp_path, monkeypatch):
    from wendel.loop import run

    monkeypatch.delenv(ENV, raising=False)
    quiet = {"smoke": True, "png": False, "progress": lambda *_: None}
    plain = run(WORKFLOWS / "smoke.toml", out=tmp_path / "plain", **quiet)
    monkeypatch.setenv(ENV, str(tmp_path / "cache"))
    cold, warm = (run(WORKFLOWS / "smoke.toml", out=tmp_path / n, **quiet) for n in ("cold", "warm"))
    s = {r.name: json.loads((r / "summary.json").read_text()) for r in (plain, cold, warm)}
    assert "mesh_cache" not in s["plain"]
    assert s["cold"]["mesh_cache"]["hit"] is False and s["warm"]["mesh_cache"]["hit"] is True
    assert s["cold"]["mesh_cache"]["key"] == s["warm"]["mesh_cache"]["key"]
    reference = _fingerprint(plain)
    assert reference["fields"] and reference["history"]
    assert _fingerprint(cold) == reference
    assert _fingerprint(warm) == reference


def test_the_mesh_cache_option_of_wendel_run(tmp_path, monkeypatch, capsys):
    from wendel.cli import main

    monkeypatch.setenv(ENV, "")              # restored after the test: the option sets the variable for good
    for n in ("a", "b"):
        assert main(["run", str(WORKFLOWS / "smoke.toml"), "--smoke", "--out", str(tmp_path / n),
                     "--mesh-cache", str(tmp_path / "cache")]) == 0
    hits = [json.loads((tmp_path / n / "summary.json").read_text())["mesh_cache"]["hit"] for n in ("a", "b")]
    assert hits == [False, True] and len(_entries(tmp_path / "cache")) == 1


@pytest.mark.parametrize("variant", [{"optimize": False}, {"optimize": False, "algorithm": "hxt"},
                                     {"algorithm": "hxt"}, {"optimize": False, "optimize_threshold": 0.6}])
def test_box_without_netgen_is_another_valid_mesh_under_another_key(variant, tmp_path, monkeypatch):
    """geometry.optimize = false and/or algorithm = "hxt" (box): gmsh's tetrahedra without the Netgen
    optimization, or by HXT instead of Delaunay, or gmsh's own optimizer up to another quality
    (optimize_threshold, hertz-force-3d's mesh): the same boundaries, another mesh (so another cache key),
    every tetrahedron of positive volume; the same keywords give the same file again (HXT on one thread)."""
    monkeypatch.setenv(ENV, str(tmp_path / "cache"))
    opt = build("box", tmp_path / "opt.msh", **BOX)
    raw = build("box", tmp_path / "raw.msh", **BOX, **variant)
    monkeypatch.delenv(ENV)
    again = build("box", tmp_path / "again.msh", **BOX, **variant)
    assert (tmp_path / "again.msh").read_bytes() == (tmp_path / "raw.msh").read_bytes() and again.cache is None
    assert raw.boundaries == opt.boundaries and raw.dimension == 3 and raw.elements > 0
    assert raw.cache["key"] != opt.cache["key"]
    assert (tmp_path / "raw.msh").read_bytes() != (tmp_path / "opt.msh").read_bytes()
    import meshio
    import numpy as np

    m = meshio.read(tmp_path / "raw.msh")
    p, t = m.points, m.cells_dict["tetra"]
    vol = np.einsum("ij,ij->i", np.cross(p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]), p[t[:, 3]] - p[t[:, 0]]) / 6
    assert np.all(np.abs(vol) > 0) and abs(np.abs(vol).sum() - 0.25) < 1e-12     # the box's volume, m^3
