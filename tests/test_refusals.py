"""What wendel refuses, and the message it gives: numbers, geometry, mesh files, sizes, options, names.

Each case checks the exit code and that the message names the file and the key (or the option / path).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from wendel.cli import main

from conftest import edit, SMOKE_SCENE, WORKFLOWS

ROOT = Path(__file__).resolve().parents[1]


NUMBERS = [
    (("E = 2.5", "E = inf"), "material.E", "finite"),
    (("E = 2.5", "E = nan"), "material.E", "finite"),
    (("E = 2.5", "E = 1e400"), "material.E", "finite"),
    (("E = 2.5", "E = true"), "material.E", "valid number"),
    (("E = 2.5", "E = \"2.5\""), "material.E", "valid number"),
    (("[boundary.top]\nux = 0.0", "[boundary.top]\nux = 1.7e308"), "boundary.top.ux", "magnitude"),
    (("value = [1.0]", "value = [-1.7e308]"), "body_force.value", "magnitude"),
    (("steps = 1", "steps = 1.0"), "loading.steps", "valid integer"),
    (("steps = 1", "steps = true"), "loading.steps", "valid integer"),
    (("ranks = 1", "ranks = \"1\""), "numerics.ranks", "valid integer"),
]

GEOMETRY = [
    (("x = [-1.0, 1.0]", "x = [1.0, -1.0]"), "geometry.x", "interval must increase"),
    (("x = [-1.0, 1.0]", "x = [-1.0, 1.0, 2.0]"), "geometry.x", "at most 2"),
    (("x = [-1.0, 1.0]", "x = [-1.0, inf]"), "geometry.x", "finite"),
    (("x = [-1.0, 1.0]", "x = [-1.0, 1.0]\nstructured = 1"), "geometry.structured", "valid boolean"),
    (("x = [-1.0, 1.0]", "x = [-1.0, 1.0]\nrefine = { center = [0.0, 0.0], radius = 0.1, h = 0.01, hh = 1.0 }"),
     "geometry.refine.hh", "unknown key"),
    (("x = [-1.0, 1.0]", "x = [-1.0, 1.0]\nrefine = { center = [0.0, 0.0], radius = 0.1 }"),
     "geometry.refine", "exactly one of refine.h or refine.ratio"),
    (("[boundary.left]", "[boundary.inner]"), "boundary.inner", "builder 'rectangle' names left, right, bottom, top"),
]


@pytest.mark.parametrize("change, key, words", NUMBERS + GEOMETRY)
def test_check_refuses_with_file_and_key(change, key, words, scene_file, capsys):
    path = scene_file(edit(SMOKE_SCENE, *change))
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}: {key}" in err, err
    assert words in err, err


OTHER_SCENES = [
    # a 3D builder's tetrahedral algorithm: "delaunay" or "hxt" (box)
    ("ball-indent.toml", ('builder = "box"', 'builder = "box"\nalgorithm = "tetgen"'), "geometry.algorithm",
     "'delaunay' or 'hxt'"),
    ("cylinder.toml", ("r_inner = 1.0", "r_inner = 2.0"), "geometry.r_inner", "smaller than r_outer"),
]


@pytest.mark.parametrize("scene, change, key, words", OTHER_SCENES)
def test_check_refuses_with_file_and_key_in_other_scenes(scene, change, key, words, scene_file, capsys):
    path = scene_file(edit((WORKFLOWS / scene).read_text(), *change))
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}: {key}" in err and words in err, err


def test_size_guards_refuse_before_meshing(scene_file, capsys):
    path = scene_file(edit(SMOKE_SCENE, "h = 0.025", "h = 1e-9"))
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}: geometry.h" in err and "numerics.max_elements" in err and "about 9.2e+18 elements" in err, err
    path = scene_file(edit(SMOKE_SCENE, "steps = 1", "steps = 1000000000"), "steps.toml")
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}: loading.steps" in err and "numerics.max_increments" in err, err
    # the limits are keys: raised, the same scene passes
    path = scene_file(edit(SMOKE_SCENE, "steps = 1", "steps = 200000").replace(
        "[numerics]", "[numerics]\nmax_increments = 300000"), "raised.toml")
    assert main(["check", str(path)]) == 0


def _mesh_scene(scene_file, mesh: Path, boundaries=("left",)) -> Path:
    text = edit(SMOKE_SCENE, 'builder = "rectangle"\nx = [-1.0, 1.0]          # m\ny = [-1.0, 1.0]          # m\n',
                f'mesh = "{mesh}"\ndimension = 2\n')
    for name in ("right", "bottom", "top"):
        if name not in boundaries:
            text = text.replace(f"[boundary.{name}]\nux = 0.0\nuy = 0.0\n", "")
    return scene_file(text)


@pytest.fixture(scope="module")
def good_mesh(tmp_path_factory):
    from wendel.meshes import build

    path = tmp_path_factory.mktemp("mesh") / "square.msh"
    build("rectangle", path, x=(-1.0, 1.0), y=(-1.0, 1.0), h=0.5)
    return path


def test_mesh_file_is_checked(good_mesh, scene_file, tmp_path, capsys):
    assert main(["check", str(_mesh_scene(scene_file, good_mesh))]) == 0
    text = good_mesh.read_text()
    bad = {
        "v41.msh": (text.replace("2.2 0 8", "4.1 0 8", 1), "MSH 4.1 file; FreeFEM reads MSH 2.2 only: convert"),
        "cut.msh": (text[: len(text) // 2], "truncated"),
        "nan.msh": (text.replace("$Nodes\n", "$Nodes\n", 1).replace("\n1 -1 -1 0\n", "\n1 nan -1 0\n", 1),
                    "non-finite coordinate"),
        "notags.msh": ("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n"
                       "$Elements\n2\n1 1 0 1 2\n2 2 0 1 2 3\n$EndElements\n", "no physical tags"),
        "inverted.msh": ("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n"
                         "$Elements\n2\n1 1 2 1 1 1 2\n2 2 2 100 1 1 3 2\n$EndElements\n", "inverted"),
        "junk.msh": ("solid\nfacet normal 0 0 1\n", "not a gmsh mesh file"),
    }
    assert "\n1 -1 -1 0\n" in text
    for name, (content, words) in bad.items():
        mesh = tmp_path / name
        mesh.write_text(content)
        path = _mesh_scene(scene_file, mesh)
        assert main(["check", str(path)]) == 2, name
        err = capsys.readouterr().err
        assert f"{path}: geometry.mesh" in err and str(mesh) in err and words in err, (name, err)


def test_boundary_names_checked_against_the_mesh_file(good_mesh, scene_file, capsys):
    text = (_mesh_scene(scene_file, good_mesh)).read_text().replace("[boundary.left]", "[boundary.inner]")
    path = scene_file(text, "inner.toml")
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert f"{path}: boundary.inner" in err and "has no physical tag 7 (inner)" in err, err


def test_remesh_indicator_is_a_field_name(scene_file, capsys):
    text = (WORKFLOWS / "upsetting.toml").read_text()
    for bad in ("../../x", "p; rm", "nosuchfield"):
        path = scene_file(edit(text, 'indicator = "p"', f'indicator = "{bad}"'))
        assert main(["check", str(path)]) == 2
        err = capsys.readouterr().err
        assert f"{path}: remesh.indicator" in err and "valid:" in err, err


def test_control_characters_are_not_printed_raw(scene_file, capsys):
    path = scene_file(edit(SMOKE_SCENE, 'description = "', 'description = "\\u001b[2J\\u0007'))
    assert main(["check", str(path)]) == 0
    out = capsys.readouterr().out
    assert "\x1b" not in out and "\x07" not in out and "\\x1b" in out, out


@pytest.mark.parametrize("value", ["0", "-1", "abc", "100000"])
def test_np_is_validated(value, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["run", str(WORKFLOWS / "smoke.toml"), "--np", value])
    assert exc.value.code == 2
    assert "--np" in capsys.readouterr().err


def test_out_that_cannot_be_a_folder(tmp_path, capsys):
    afile = tmp_path / "afile"
    afile.write_text("x")
    for out in (afile, afile / "below", Path("/proc/wendel-cannot-write")):
        assert main(["run", str(WORKFLOWS / "smoke.toml"), "--smoke", "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert "--out" in err and str(out) in err, err


def test_resume_says_what_it_ignores(tmp_path, capsys):
    run = tmp_path / "r"
    assert main(["run", str(WORKFLOWS / "smoke-mms.toml"), "--smoke", "--out", str(run)]) == 0
    capsys.readouterr()
    assert main(["run", str(WORKFLOWS / "smoke.toml"), "--resume", str(run), "--np", "1"]) == 0
    out = capsys.readouterr().out
    assert "ignored with --resume" in out and "smoke.toml" in out and "--np" in out, out


def test_run_without_vtu(tmp_path):
    text = edit(SMOKE_SCENE, "[reference]", "[output]\nvtu = false\n\n[reference]")
    scene = tmp_path / "novtu.toml"
    scene.write_text(text)
    assert main(["run", str(scene), "--smoke", "--out", str(tmp_path / "r")]) == 0
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["increments"] == 1
    assert not (tmp_path / "r" / "vtu").exists() and not (tmp_path / "r" / "results.pvd").exists()


def test_log_errors_are_located_in_project_files_only():
    from wendel.freefem import explain_log

    script = ROOT / "edp" / "mechanics.edp"
    log = ("Error line number 1, in file /etc/shadow, before  token x\n"
           f"Error line number 12, in file {ROOT / 'edp' / 'lib' / 'bc.idp'}, before  token y\n")
    message, file, line = explain_log(log, script)
    assert file is not None and file.endswith("edp/lib/bc.idp") and line == 12, (message, file, line)
    message, file, line = explain_log("Error line number 1, in file /etc/shadow, before  token x\n", script)
    assert file is None or "/etc/shadow" not in file, (message, file)


def test_inverted_elements_without_remeshing_are_reported(tmp_path, capsys):
    # upsetting by 50 % without its [remesh] table inverts the corner elements at the platens
    text = (WORKFLOWS / "upsetting.toml").read_text()
    text = text.split("[remesh]")[0] + "[reference]" + text.split("[reference]")[1]
    scene = tmp_path / "no-remesh.toml"
    scene.write_text(text)
    assert main(["run", str(scene), "--smoke", "--out", str(tmp_path / "r")]) == 0
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["warnings"] and "inverted elements (no [remesh] table)" in summary["warnings"][0]
    assert "warning: increments" in capsys.readouterr().out


def test_failed_run_reports_the_bracket(tmp_path, scene_file, capsys):
    text = SMOKE_SCENE.replace("[numerics]", "[numerics]\nnewton_maxit = 3\nnewton_tol = 1e-300")
    text = text.replace("[loading]\nsteps = 1", "[loading]\nsteps = 1\nmax_cuts = 1")
    assert main(["run", str(scene_file(text)), "--smoke", "--out", str(tmp_path / "r")]) == 1
    assert "between load factor 0 (last converged) and 0.5 (first failed)" in capsys.readouterr().err
    stopped = json.loads((tmp_path / "r" / "summary.json").read_text())["stopped"]
    assert stopped["last_converged_load_factor"] == 0.0 and stopped["first_failed_load_factor"] == 0.5


@pytest.mark.parametrize("content, words", [
    (b"\x89PNG\r\n\x1a\n" + b"0" * 64, "is not a PGM or PPM image"),
    (b"P2\n100000 100000\n255\n1 2 3\n", "is 100000 x 100000 pixels"),
    (b"P2\n# only a comment\n", "unreadable PGM/PPM header"),
])
def test_heightmap_images_are_checked(content, words, tmp_path, capsys):
    image = tmp_path / "map.pgm"
    image.write_bytes(content)
    text = (WORKFLOWS / "stamp-indent.toml").read_text()
    start = text.index("image = ")
    text = text[:start] + f'image = "{image}"' + text[text.index("\n", start):]
    scene = tmp_path / "stamp.toml"
    scene.write_text(text)
    assert main(["check", str(scene)]) == 2
    err = capsys.readouterr().err
    assert f"{scene}: contact" in err and "contact.image" in err and words in err, err
