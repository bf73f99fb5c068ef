"""The driver's layout rules: packages by stage, all of them installed, no long module without a reason."""

import ast
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DRIVER = ROOT / "driver" / "wendel"
MAX_LINES = 300


def test_every_driver_package_is_in_pyproject():
    packages = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(("wendel",) + d.relative_to(DRIVER).parts).rstrip(".") for d in [DRIVER, *DRIVER.rglob("*")]
             if d.is_dir() and (d / "__init__.py").is_file()}
    assert found and found <= packages, sorted(found - packages)


def test_a_module_above_300_lines_says_why_in_its_docstring():
    long = {}
    for f in sorted(DRIVER.rglob("*.py")):
        text = f.read_text()
        if text.count("\n") > MAX_LINES:
            long[f.relative_to(DRIVER).as_posix()] = "on purpose" in (ast.get_docstring(ast.parse(text)) or "")
    assert all(long.values()), [name for name, ok in long.items() if not ok]
