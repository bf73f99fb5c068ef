"""The Newton method of the updated-Lagrangian kinematics: its tangent against finite differences of its residual
(edp/lib/fdcheck.idp, -newton_fd_check), and the extrapolated first guess of an increment (numerics.predictor,
edp/lib/predictor.idp) on the 3D tension cube of `wendel bench ul`."""

from __future__ import annotations

import csv
import tomllib
from pathlib import Path

import pytest

from wendel import freefem
from wendel.loop import run
from wendel.results import vtu as output

from conftest import WORKFLOWS


def tension_cube(scene_file, name: str, strain: float, steps: int, extra: str = "") -> Path:
    """ul-tension-3d.toml on a mesh of h = 0.5 m, pulled to ``strain`` in ``steps`` increments."""
    text = (WORKFLOWS / "ul-tension-3d.toml").read_text()
    for old, new in (("uz = 1.0 ", f"uz = {strain!r} "), ("steps = 20", f"steps = {steps}"),
                     ("[output]", f"{extra}\n[output]")):      # extra: keys of [numerics], the table before
        assert old in text
        text = text.replace(old, new, 1)
    return scene_file(text, f"{name}.toml")


def rows(path: Path) -> list[dict]:
    with open(path) as f:
        return list(csv.DictReader(f))


def relaunch(root: Path, out: Path, *extra: str) -> Path:
    """The run's FreeFEM launch again with more options, into ``out``."""
    words = (root / "freefem.log").read_text().splitlines()[0].split()
    opts = words[words.index("-out") + 2:]
    freefem.run("mechanics.edp", opts + list(extra), out)
    return out


def fd_differences(root: Path, out: Path) -> tuple[list[float], list[float]]:
    """The run's launch again with the finite-difference check into ``out``: the relative differences along the
    Newton steps and in random directions (past each increment's start)."""
    fd = rows(relaunch(root, out, "-newton_fd_check", "1e-6") / "fdcheck.csv")
    newton = [float(r["relative_difference"]) for r in fd if r["direction"] == "newton"]
    random = [float(r["relative_difference"]) for r in fd if r["direction"] == "random" and r["iteration"] != "0"]
    return newton, random


@pytest.mark.parametrize("volumetric", ["cell", "fbar"])
def test_3d_tangent_matches_the_residual_differences_at_a_deformed_plastic_state(scene_file, tmp_path, quiet,
                                                                                 volumetric):
    # 3 increments of 1 % (plastic from the first): the tangent along each Newton direction is the residual's
    # derivative to the difference quotient's accuracy (measured 2e-10 to 4e-9), so Newton is quadratic; in a
    # random direction the derivative of ln V taken as sym grad shows, of the order of the increment's strain
    # times the plastic tangent (measured 1e-5 to 1.5e-5 at 1 %, 1.5e-4 to 2.4e-4 at 10 %); at the start of the
    # first increment (f = I, elastic) it is exact. F-bar: its patch term through the augmented solve
    # (kinematics-fbar.idp; a homogeneous state, but the random direction is not)
    scene = tension_cube(scene_file, "fd", 0.03, 3)
    scene.write_text(scene.read_text().replace('kind = "updated-lagrangian"',
                                               f'kind = "updated-lagrangian"\nvolumetric = "{volumetric}"'))
    root = run(scene, out=tmp_path / "run", progress=quiet, png=False)
    out = relaunch(root, tmp_path / "fd", "-newton_fd_check", "1e-6")
    fd = rows(out / "fdcheck.csv")
    newton = [float(r["relative_difference"]) for r in fd if r["direction"] == "newton"]
    random = [float(r["relative_difference"]) for r in fd if r["direction"] == "random" and r["iteration"] != "0"]
    start = [float(r["relative_difference"]) for r in fd if (r["increment"], r["iteration"]) == ("1", "0")]
    assert len(newton) >= 6 and max(newton) < 1e-7
    assert len(random) == len(newton) and 1e-7 < max(random) < 1e-3
    assert len(start) == 1 and start[0] < 1e-8
    # the check leaves the Newton path alone
    for inc in ("inc-0001", "inc-0002", "inc-0003"):
        plain = [r["residual"] for r in rows(root / "fem" / inc / "newton.csv")]
        assert [r["residual"] for r in rows(out / inc / "newton.csv")] == plain


@pytest.mark.parametrize("name", ["ul-compression", "ul-compression-axi"])
def test_2d_tangent_is_the_residual_derivative_in_every_direction(tmp_path, quiet, name):
    # Plane strain and (r, z) compression with hardening, 2-10 % an increment: the tangent carries the exact
    # derivative of the strain update (the polar angle and ln V of the increment, kinematics.idp's ulExact), so
    # it equals the residual's central differences along the Newton step and in a random direction (measured
    # 2e-9 and 5e-10 at most; with the Jaumann spin and sym grad standing for them the random direction
    # differed by up to 1.4e-3 on the plane-strain block)
    root = run(WORKFLOWS / f"{name}.toml", smoke=True, out=tmp_path / "run", progress=quiet, png=False)
    newton, random = fd_differences(root, tmp_path / "fd")
    assert len(newton) >= 10 and len(random) == len(newton)
    assert max(newton) < 1e-7 and max(random) < 1e-7


BARREL = """description = "Plane-strain block between sticking platens: barrelling, an inhomogeneous plastic state"
[geometry]
builder = "rectangle"
x = [0.0, 1.0]           # m
y = [0.0, 1.0]           # m
h = 0.125                # m
[material]
E = 70e9                 # Pa
nu = 0.3                 # 1
[plasticity]
law = "linear"
sigma0 = 250e6           # Pa
H = 1e9                  # Pa
[kinematics]
kind = "updated-lagrangian"
volumetric = "fbar"
[boundary.left]
ux = 0.0                 # m (symmetry)
[boundary.bottom]
ux = 0.0                 # m (sticking platen)
uy = 0.0                 # m
[boundary.top]
ux = 0.0                 # m (sticking platen)
uy = -0.2                # m at load factor 1: 20 % of the height
[loading]
steps = 4
[numerics]
newton_tol = 1e-10
newton_maxit = 40
[output]
png = false
"""


def test_plane_strain_fbar_tangent_is_the_residual_derivative_on_an_inhomogeneous_plastic_state(scene_file,
                                                                                               tmp_path, quiet):
    # The cut's formulation (plane strain, F-bar: the patch term Y' diag(1 / s) Z added to K with the plastic
    # N term of Q, kinematics-fbar.idp) on a barrelling block (4 increments of 5 %): measured 2e-7 along the
    # Newton steps and 3e-8 in random directions (session 19, while tracing the F-bar cut's inversions at the
    # tool's edge: the tangent is not their cause)
    root = run(scene_file(BARREL, "barrel.toml"), out=tmp_path / "run", progress=quiet, png=False)
    newton, random = fd_differences(root, tmp_path / "fd")
    assert len(newton) >= 20 and len(random) == len(newton)
    assert max(newton) < 1e-6 and max(random) < 1e-6


def test_extrapolated_predictor_saves_a_newton_iteration_per_increment(scene_file, tmp_path, quiet):
    # 5 increments of 1 %: from the accepted state each plastic increment takes 3 Newton iterations (relative
    # residuals 0.016, 3e-7, 1e-14: quadratic, the first step's error is the path's curvature); from the
    # extrapolated guess (residual 0.03) 2 (1e-6, 1e-14), once the previous increment was a plastic one
    its, stress = {}, {}
    for predictor in ("none", "extrapolate"):
        scene = tension_cube(scene_file, predictor, 0.05, 5, f'predictor = "{predictor}"')
        root = run(scene, out=tmp_path / predictor, progress=quiet, png=False)
        its[predictor] = [len(rows(d / "newton.csv")) - 1 for d in sorted((root / "fem").glob("inc-*"))]
        stress[predictor] = output.read_array(root / "fem" / "inc-0005" / "stress_zz.cell.txt")
    assert its["none"][2:] == [3, 3, 3]
    assert its["extrapolate"][2:] == [2, 2, 2]
    assert its["extrapolate"][:2] == its["none"][:2] or sum(its["extrapolate"]) < sum(its["none"])
    assert abs(stress["extrapolate"] - stress["none"]).max() <= 1e-10 * abs(stress["none"]).max()


def test_on_a_nonlinear_3d_path_updated_lagrangian_takes_the_newton_steps_of_small_strain(scene_file, tmp_path,
                                                                                            quiet):
    # the cube of `wendel bench ul`'s 3d-voce rows: the necking bar's saturating hardening (Simo 1988) makes
    # small strain's path nonlinear too (with linear hardening it closes each plastic increment in one step),
    # and then the updated-Lagrangian run needs about as many Newton iterations (measured 15 against 16)
    bar = tomllib.loads((WORKFLOWS / "ul-necking-bar.toml").read_text())
    steel = "".join(f"[{table}]\n" + "".join(f"{k} = {v!r}\n" for k, v in bar[table].items()) + "\n"
                    for table in ("material", "plasticity"))
    its = {}
    for kind in ("small-strain", "updated-lagrangian"):
        scene = tension_cube(scene_file, kind, 0.05, 5)
        text = scene.read_text()
        text = text.replace(text[text.index("[material]"):text.index("[kinematics]")], steel)
        scene.write_text(text.replace('kind = "updated-lagrangian"', f'kind = "{kind}"'))
        root = run(scene, out=tmp_path / kind, progress=quiet, png=False)
        its[kind] = [len(rows(d / "newton.csv")) - 1 for d in sorted((root / "fem").glob("inc-*"))]
    assert all(n >= 2 for n in its["small-strain"][1:]), its         # plastic from the 2nd increment: nonlinear
    assert sum(its["updated-lagrangian"]) <= sum(its["small-strain"]) + 2, its
