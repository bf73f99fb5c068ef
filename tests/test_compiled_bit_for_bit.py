"""Per-point work compiled against the array code it replaces, on every launch (`-plast_compiled 0
-ul_exact_compiled 0`): Johnson-Cook's return mapping (edp/plugins/wendel_plast.cpp, plastReturn of
edp/lib/plasticity.idp) and the exact derivative of the plane updated-Lagrangian strain update
(wendelUlExact2 of edp/plugins/wendel_ul.cpp, ulExact of edp/lib/kinematics.idp). The same runs bit for bit:
every cell, node and state file of every increment and every record entry but the timers. On the FE cut (2D,
updated-Lagrangian with F-bar, heat by conduction, rate-dependent, remeshed: a re-equilibration without time
runs on the kept rate factors), the 3D JC cube with and without the compiled element kernels (their points'
subsets), the 2D heated indentation (monolithic heat, rate-dependent), the (r, z) necking bar (F-bar, Voce)
and the plane plastic shear to large strain."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from conftest import WORKFLOWS
from wendel import freefem

ARRAY_CODE = ["-plast_compiled", "0", "-ul_exact_compiled", "0"]


def _same_increments(a: Path, b: Path) -> int:
    """The number of increments, after checking that both runs wrote the same ones with the same bytes."""
    incs = sorted(p.name for p in a.glob("inc-*") if (p / "done").is_file())
    assert incs and incs == sorted(p.name for p in b.glob("inc-*") if (p / "done").is_file())
    for inc in incs:
        files = sorted(p.name for p in (a / inc).iterdir())
        assert files == sorted(p.name for p in (b / inc).iterdir()), inc
        for f in files:
            if f == "record.json":
                ra, rb = (json.loads((d / inc / f).read_text()) for d in (a, b))
                assert ra.keys() == rb.keys()
                assert {k: v for k, v in ra.items() if not k.startswith("time")} == \
                       {k: v for k, v in rb.items() if not k.startswith("time")}, inc
            else:
                assert (a / inc / f).read_bytes() == (b / inc / f).read_bytes(), (inc, f)
    return len(incs)


def _array_code(monkeypatch):
    """Every later launch with the array code."""
    command = freefem._command
    monkeypatch.setattr(freefem, "_command", lambda entry, options, *a, **k:
                        command(entry, [*options, *ARRAY_CODE], *a, **k))


def test_cut_compiled_is_the_array_codes_bit_for_bit(tmp_path, monkeypatch):
    from wendel.cutting.fe_run import run_cut
    from wendel.scene import load
    path = WORKFLOWS / "cutting-aisi1045.toml"

    def cut(out):
        scene = load(path, smoke=True)
        scene.cutting.volumetric = "fbar"
        scene.thermal.coupling = "staggered"      # the steady scenes' heat: plastReturn with the point temperatures
        scene.cutting.remesh_every = 2
        return run_cut(scene, path, out, smoke=True, progress=lambda *_: None, frames=False)

    monkeypatch.setenv("WENDEL_PRESTART", "0")
    compiled = cut(tmp_path / "compiled")
    _array_code(monkeypatch)
    array = cut(tmp_path / "array")
    log = (array / "freefem.log").read_text()
    assert "-plast_compiled 0" in log and "-plast_compiled" not in (compiled / "freefem.log").read_text()
    assert "-DUPDATEDLAGRANGIAN=1" in log and "-therm_coupling 1" in log and "-plast_jc_C 0.0134" in log
    assert _same_increments(compiled / "fem", array / "fem") >= 4
    rows = [list(csv.DictReader((d / "history.csv").open())) for d in (compiled, array)]
    assert [{k: v for k, v in r.items() if not k.startswith("time")} for r in rows[0]] == \
           [{k: v for k, v in r.items() if not k.startswith("time")} for r in rows[1]]
    reeq = [r for r in rows[0] if r["reequilibration"] == "1"]
    assert reeq                                    # a re-equilibration without time (the kept rate factors)
    # where the last launch's seconds go (python -m wendel.bench.profile): every hook of a cut timed, within the launch
    from wendel.bench.profile import last_launch, profile_once, table
    prof = profile_once(last_launch(compiled), [])
    hooks = ("module_trial", "thermal_residual", "tangent_matrix", "module_constrain", "solve")
    assert all(prof[h][1] > 0 for h in hooks)
    assert 0 < sum(v for h, (v, _) in prof.items() if h != "launch_wall") < prof["launch_wall"][0]
    assert "| solve |" in table([prof], [prof])


@pytest.mark.parametrize("scene, assembly", [("uniaxial-jc", "freefem"), ("uniaxial-jc", "compiled"),
                                             ("thermo-indent", "freefem"), ("ul-necking-bar", "freefem"),
                                             ("ul-shear-plastic", "freefem")])
def test_scene_compiled_is_the_array_codes_bit_for_bit(tmp_path, monkeypatch, scene, assembly):
    from wendel.loop import run
    text = (WORKFLOWS / f"{scene}.toml").read_text()
    if assembly == "compiled":
        text = text.replace("[numerics]\n", '[numerics]\nassembly = "compiled"\n')
    path = tmp_path / f"{scene}.toml"
    path.write_text(text)
    monkeypatch.setenv("WENDEL_PRESTART", "0")
    compiled = run(path, smoke=True, out=tmp_path / "compiled", png=False, progress=lambda *_: None)
    _array_code(monkeypatch)
    array = run(path, smoke=True, out=tmp_path / "array", png=False, progress=lambda *_: None)
    log = (array / "freefem.log").read_text()
    assert "-plast_compiled 0" in log and "-plast_compiled" not in (compiled / "freefem.log").read_text()
    assert ("-plast_law 2" in log) == (scene in ("uniaxial-jc", "thermo-indent"))
    assert ("-DUPDATEDLAGRANGIAN=1" in log) == scene.startswith("ul-")
    assert _same_increments(compiled / "fem", array / "fem") >= 2
