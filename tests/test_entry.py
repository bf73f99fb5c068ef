"""One entry script per problem: the driver's -D macros choose what FreeFEM compiles.

FreeFEM at verbosity 1 lists every source line it compiles, the lines of included files with them. Each
module file defines its guard macro (``macro wendelPlasticityIdp 1``) on its first compiled line, so the
listing names the modules a launch compiled. The launches are real runs of one increment at the scenes'
smoke sizes, with the options and -D switches the driver builds.
"""

from __future__ import annotations

import json
import re
import subprocess

import pytest

from wendel import freefem
from wendel.loop import RunFiles, entry_script, macros, options, write_tables
from wendel.meshes import build
from wendel.scene import load

from conftest import WORKFLOWS

GUARDS = {"plasticity": "wendelPlasticityIdp", "contact": "wendelContactIdp", "thermal": "wendelThermalIdp",
          "thermal-fields": "wendelThermalFieldsIdp", "elasticity": "wendelElasticityIdp",
          "axisymmetric": "wendelAxisymmetricIdp", "axisymmetric-mechanics": "wendelAxisymmetricMechanicsIdp",
          "remeshstop": "wendelRemeshStopIdp", "kinematics": "wendelKinematicsIdp",
          "friction": "wendelFrictionIdp", "tool": "wendelToolIdp", "petsc": "wendelPetscIdp", "dg": "wendelDgIdp",
          "dg3d": "wendelDg3dIdp", "kinematics-thermal": "wendelKinematicsThermalIdp",
          "dg-plastic-p2": "wendelDgPlasticP2Idp"}
MODULES = ("plasticity", "contact", "thermal", "thermal-fields", "axisymmetric", "axisymmetric-mechanics", "remeshstop",
           "kinematics", "friction", "tool", "dg", "dg3d", "kinematics-thermal", "dg-plastic-p2")


def compiled(tmp_path, scene_name: str, solver: str | None = None, kinematics: str | None = None
             ) -> tuple[set[str], list[str], dict]:
    """Launch the scene's entry at verbosity 1; return (modules compiled, -D switches, first record)."""
    scene = load(WORKFLOWS / scene_name, smoke=True)
    if solver:
        scene.numerics.solver = solver
    if kinematics:
        scene.kinematics.kind = kinematics
    files = RunFiles(tmp_path / scene_name.removesuffix(".toml"))
    files.root.mkdir(parents=True)
    dimension = build(scene.geometry.builder, files.mesh, **scene.geometry.params).dimension
    write_tables(scene, files, dimension)
    loads = files.tables / "loads.txt"
    loads.write_text("1\n" + repr(scene.loading.load_factors()[0]) + "\n")
    switches = macros(scene, dimension)
    cmd = ["mpirun", "-np", "1", "FreeFem++-mpi", "-nw", "-v", "1", str(freefem.EDP / entry_script(scene, dimension)),
           *switches, "-out", str(files.fem), *options(scene, files, dimension), "-loads", str(loads)]
    files.fem.mkdir()
    p = subprocess.run(cmd, env=freefem.environment(), capture_output=True, text=True, timeout=300, cwd=files.root)
    assert p.returncode == 0, p.stdout[-3000:] + p.stderr[-2000:]
    listing = p.stdout
    found = {name for name, guard in GUARDS.items() if re.search(rf"macro\s+{guard}\b", listing)}
    record = json.loads((files.fem / "inc-0001" / "record.json").read_text())
    return found, switches, record


def test_an_elastic_scene_compiles_no_plasticity_contact_or_thermal_code(tmp_path):
    found, switches, record = compiled(tmp_path, "smoke.toml")
    assert switches == ["-Ddimension=2", "-DPk=P1"]
    assert "elasticity" in found                     # the listing does show the modules it compiled
    assert not found & set(MODULES), found
    assert record["newton_iterations"] >= 1


@pytest.mark.parametrize("scene_name, modules", [
    ("ball-indent.toml", {"contact", "plasticity"}),
    ("thermo-indent.toml", {"contact", "plasticity", "thermal", "thermal-fields"}),
    ("sliding-block.toml", {"contact", "friction", "tool"}),
])
def test_each_block_compiles_its_module_and_only_it(tmp_path, scene_name, modules):
    found, switches, _ = compiled(tmp_path, scene_name)
    assert found & set(MODULES) == modules, found
    assert {f"-DWITH{m.upper()}=1" for m in modules if m not in ("thermal-fields", "tool")} <= set(switches)


def test_only_a_petsc_scene_loads_the_petsc_plugin(tmp_path):
    found, switches, record = compiled(tmp_path / "cg", "ball-indent.toml", solver="cg")
    assert "petsc" not in found and "-DWITHPETSC=1" not in switches
    found, switches, record = compiled(tmp_path / "petsc", "ball-indent.toml")     # the scene's own solver
    assert "petsc" in found and "-DWITHPETSC=1" in switches
    assert record["petsc_setups"] >= 1


def test_updated_lagrangian_kinematics_is_compiled_only_when_the_scene_asks(tmp_path):
    found, switches, _ = compiled(tmp_path, "ul-tension.toml")
    assert found & set(MODULES) == {"plasticity", "kinematics"} and "-DUPDATEDLAGRANGIAN=1" in switches


def test_updated_lagrangian_heat_compiles_its_forms_only_with_both_switches(tmp_path):
    """thermo-free.toml with updated-Lagrangian kinematics: the heat equation on the current configuration
    (kinematics-thermal.idp) beside thermal and kinematics; ul-tension.toml (no [thermal]) and thermo-indent.toml
    (small strain) do not compile it (test_updated_lagrangian_kinematics_is_compiled_only_when_the_scene_asks,
    test_each_block_compiles_its_module_and_only_it)."""
    found, switches, record = compiled(tmp_path, "thermo-free.toml", kinematics="updated-lagrangian")
    assert found & set(MODULES) == {"thermal", "thermal-fields", "kinematics", "kinematics-thermal"}, found
    assert "-DUPDATEDLAGRANGIAN=1" in switches and "-DWITHTHERMAL=1" in switches
    assert record["max_temperature"] > 393.0


def test_a_value_of_zero_still_switches_a_module_on(tmp_path):
    # IFMACRO tests whether a macro is defined, not its value: the driver leaves a switch out, never passes 0
    script = tmp_path / "probe.edp"
    script.write_text('IFMACRO(WITHPLASTICITY)\ncout << "on " << WITHPLASTICITY << endl;\nENDIFMACRO\n'
                      'IFMACRO(dimension,3)\ncout << "3D" << endl;\nENDIFMACRO\ncout << "end" << endl;\n')
    run = lambda *d: subprocess.run(["FreeFem++-mpi", "-nw", "-v", "0", str(script), *d], env=freefem.environment(),
                                    capture_output=True, text=True, timeout=60).stdout
    assert "on 0" in run("-DWITHPLASTICITY=0")
    assert "on" not in run("-DWITHPLASTICITY")          # no "=": nothing is defined
    assert "3D" in run("-Ddimension=3") and "3D" not in run("-Ddimension=2")


def test_the_entry_refuses_a_launch_without_dimension(tmp_path):
    with pytest.raises(freefem.FreeFemError, match="-Ddimension=2 or -Ddimension=3"):
        freefem.run("mechanics.edp", [], tmp_path / "out")
