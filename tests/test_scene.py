"""Scene validation: bad scenes are rejected with a message naming the file and the key."""

import re

import pytest

from wendel.cli import main
from wendel.scene import SceneError, load

from conftest import edit, SMOKE_SCENE


BAD = [
    # (change to the smoke scene, expected key, expected words)
    (("E = 2.5", "E = -2.5"), "material.E", "greater than 0"),
    (("E = 2.5", "E = 0.0"), "material.E", "greater than 0"),
    (("nu = 0.25", "nu = 0.5"), "material.nu", "less than 0.5"),
    (("nu = 0.25", "nu = -1.2"), "material.nu", "greater than -1"),
    (("h = 0.025", "h = 0.0"), "geometry.h", "greater than 0"),
    (("h = 0.025", "h = \"fine\""), "geometry.h", "valid number"),
    (("[material]", "[material]\nrho = 7800.0"), "material.rho", "unknown key"),
    (("[numerics]", "[numerix]"), "numerix", "unknown key"),
    (("builder = \"rectangle\"", "builder = \"hexagon\""), "geometry", "unknown builder 'hexagon'; valid: axi_rectangle, box,"),
    (("x = [-1.0, 1.0]", "x = [-1.0, 1.0]\nradius = 2.0"), "geometry", "unknown key(s) radius for builder 'rectangle'"),
    (("solver = \"ffddm\"", "solver = \"amgx\""), "numerics.solver", "unknown solver 'amgx'; valid: direct, cg, ffddm, petsc"),
    (("ranks = 1", "ranks = 0"), "numerics.ranks", "greater than or equal to 1"),
    (("kind = \"step8-discs\"", "kind = \"gravity\""), "body_force.kind", "unknown body force 'gravity'"),
    (("[boundary.left]", "[boundary.west]"), "boundary.west", "unknown boundary name"),
    (("steps = 1", "steps = 0"), "loading.steps", "greater than or equal to 1"),
    (("plane = \"strain\"", "plane = \"membrane\""), "elasticity.plane", "'strain', 'stress' or 'axisymmetric'"),
    (("ranks = 1\nsolver = \"ffddm\"", "ranks = 2\nsolver = \"direct\""), "numerics", "runs on one rank"),
    (("description = ", "descr = "), "description", "Field required"),
]


@pytest.mark.parametrize("change,key,words", BAD, ids=[b[1] + ":" + b[2][:20] for b in BAD])
def test_bad_scene_is_rejected_with_file_and_key(scene_file, change, key, words):
    path = scene_file(edit(SMOKE_SCENE, *change))
    with pytest.raises(SceneError) as exc:
        load(path)
    msg = str(exc.value)
    assert f"{path}: {key}" in msg
    assert words in msg


def test_malformed_toml_names_the_file(scene_file):
    path = scene_file(SMOKE_SCENE + "\n[geometry\n")
    with pytest.raises(SceneError, match=re.escape(str(path)) + ": not valid TOML"):
        load(path)


def test_missing_scene_and_missing_mesh(tmp_path, scene_file):
    with pytest.raises(SceneError, match="no such scene file"):
        load(tmp_path / "nope.toml")
    text = edit(SMOKE_SCENE, "builder = \"rectangle\"\nx = [-1.0, 1.0]          # m\ny = [-1.0, 1.0]          # m\n",
                "mesh = \"missing.msh\"\ndimension = 2\n")
    path = scene_file(text)
    with pytest.raises(SceneError, match=r"geometry.mesh: no such file .*missing.msh"):
        load(path)


def test_check_cli_exit_codes(scene_file, capsys):
    good = scene_file(SMOKE_SCENE, "good.toml")
    assert main(["check", str(good)]) == 0
    bad = scene_file(edit(SMOKE_SCENE, "E = 2.5", "E = -1.0"), "bad.toml")
    assert main(["check", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.toml: material.E" in err


def test_smoke_override(scene_file):
    s = load(scene_file(SMOKE_SCENE), smoke=True)
    assert s.geometry.h == 0.1
    assert load(scene_file(SMOKE_SCENE)).geometry.h == 0.025


def test_every_workflow_validates_and_declares_a_smoke_size():
    from conftest import WORKFLOWS

    for path in sorted(WORKFLOWS.glob("*.toml")):
        s = load(path)
        assert s.description.strip(), path
        assert s.smoke.h is not None or s.smoke.steps is not None, f"{path}: no [smoke] size"


BLOCK_BAD = [
    ("hertz.toml", ('obstacle = "ball"', 'obstacle = "cube"'), "contact.obstacle",
     "unknown obstacle 'cube'; valid: plane, ball, cylinder, heightmap"),
    ("hertz.toml", ('boundary = "top"', 'boundary = "lid"'), "contact.boundary", "unknown boundary 'lid'"),
    ("cylinder.toml", ('law = "perfect"', 'law = "plastic"'), "plasticity.law", "unknown"),
    ("cylinder.toml", ("sigma0 = 250e6", "sigma0 = -250e6"), "plasticity.sigma0", "greater than 0"),
    ("thermo-indent.toml", ('coupling = "monolithic"', 'coupling = "loose"'), "thermal.coupling",
     "unknown coupling 'loose'"),
    ("thermo-indent.toml", ("k = 44.5 ", "k = -44.5 "), "thermal.k", "greater than 0"),
]


@pytest.mark.parametrize("scene,change,key,words", BLOCK_BAD, ids=[b[2] for b in BLOCK_BAD])
def test_bad_physics_block_is_rejected_with_file_and_key(scene_file, scene, change, key, words):
    from conftest import WORKFLOWS

    path = scene_file(edit((WORKFLOWS / scene).read_text(), *change))
    with pytest.raises(SceneError) as exc:
        load(path)
    assert f"{path}: {key}" in str(exc.value)
    assert words in str(exc.value)


def test_values_reach_freefem_as_numbers_only(tmp_path):
    """A scene string never reaches FreeFEM as code: every option value is a number, a validated name (a solver,
    a PETSc preconditioner preset), a path the driver wrote, or the PETSc options string that passed its check."""
    from conftest import WORKFLOWS
    from wendel.loop import RunFiles, options
    from wendel.cutting.fe import fe_scene
    from wendel.scene.petsc import PRECONDITIONERS, check_options
    from wendel.scene.schema import SOLVERS

    for path in sorted(WORKFLOWS.glob("*.toml")):
        scene = load(path)
        if scene.cutting is not None:
            scene = fe_scene(scene)     # a cut runs the mechanics scene it derives (wendel.cutting.fe)
        files = RunFiles(tmp_path / path.stem)
        opts = options(scene, files, 3 if scene.geometry.builder == "box" else 2)
        values = opts[1::2]
        for key, value in zip(opts[0::2], values):
            assert key.startswith("-"), (path.name, key)
            if value.startswith(str(tmp_path)) or value.startswith("/"):
                continue
            if key == "-petsc_options":     # one string for PETSc's option parser, never FreeFEM code
                assert check_options(value) == value, (path.name, key, value)
                continue
            try:
                float(value)
            except ValueError:
                assert value in {*SOLVERS, *PRECONDITIONERS}, (path.name, key, value)
