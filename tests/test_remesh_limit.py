"""gmsh with a time limit (``remesh.mesh_timeout``, :mod:`wendel.remesh.limit`): the remesh made in a worker process
is the one the driver makes, a worker that takes too long is stopped, and the loop then tries the next gmsh 2D
algorithm and at the end stops with a message that names the limit, keeping the accepted increments."""

import csv

import numpy as np
import pytest

from wendel.errors import RemeshFailure
from wendel.remesh import limit, mesher

from conftest import WORKFLOWS
from test_remesh_transfer import _labelled_box, _shear


def test_the_worker_makes_the_drivers_mesh_and_a_late_one_is_stopped(tmp_path):
    rect = _labelled_box(tmp_path / "rect.msh", 0.1, 2)
    x = _shear(mesher.read_mesh(rect)[0])
    here = mesher.remesh(x, rect, tmp_path / "here.msh", h=0.03)
    worker = limit.Worker(60.0)
    there = worker(x, rect, tmp_path / "there.msh", h=0.03)
    assert (tmp_path / "there.msh").read_bytes() == (tmp_path / "here.msh").read_bytes()
    assert {k: v for k, v in there.items() if k not in ("seconds", "path")} == \
        {k: v for k, v in here.items() if k not in ("seconds", "path")}
    pid = worker.proc.pid
    with pytest.raises(ValueError, match="^deformed mesh has .* inverted"):    # the mesher's errors come back
        worker(x * np.array([-1.0, 1.0, 1.0]), rect, tmp_path / "bad.msh", h=0.03)
    assert worker.proc.pid == pid                           # ... and the worker goes on
    worker.timeout = 1e-4                                   # no mesh in 0.1 ms: stopped, killed
    with pytest.raises(limit.MeshTimeout, match="remesh.mesh_timeout = 0.0001 s"):
        worker(x, rect, tmp_path / "late.msh", h=0.01)
    assert worker.proc is None and not isinstance(limit.MeshTimeout("x"), OSError)
    worker.timeout = 60.0                                   # a new worker for the next mesh
    assert worker(x, rect, tmp_path / "again.msh", h=0.03)["elements"] == here["elements"]
    worker.close()


def test_a_cut_whose_remeshes_all_time_out_stops_with_the_limit_named(tmp_path, monkeypatch):
    """The steel cut, remeshed after its second increment, with a limit no mesh meets: gmsh's default, Delaunay and
    MeshAdapt are each stopped, then the run stops (exit 1) naming the limit; the 2 increments are kept."""
    from wendel.cutting import fe
    from wendel.cutting.fe_run import run_cut
    from wendel.scene import load
    monkeypatch.setattr(fe, "MESH_TIMEOUT", 1e-4)
    scene = load(WORKFLOWS / "cutting-aisi1045.toml", smoke=True)
    scene.geometry.model_extra["length"] = 1.2e-3
    scene.cutting.remesh_every = 2
    said = []
    with pytest.raises(RemeshFailure) as err:
        run_cut(scene, WORKFLOWS / "cutting-aisi1045.toml", tmp_path / "cut", smoke=True, progress=said.append,
                frames=False)
    assert "remesh 1 after increment 2" in str(err.value) and "remesh.mesh_timeout = 0.0001 s" in str(err.value)
    assert [s for s in said if "MeshTimeout" in s] == [
        "  remesh 1: MeshTimeout: gmsh did not mesh the deformed body within remesh.mesh_timeout = 0.0001 s (stopped); "
        f"meshing with gmsh algorithm {a}" for a in (5, 1)]
    assert len(list(csv.DictReader((tmp_path / "cut" / "history.csv").open()))) == 2
    assert limit.mesher(1e-4).proc is None                  # no worker left behind
