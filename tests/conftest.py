"""Shared fixtures: scene files written on the fly, and small runs of the real FreeFEM."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
WORKFLOWS = ROOT / "workflows"

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

SMOKE_SCENE = (WORKFLOWS / "smoke.toml").read_text()


@pytest.fixture
def scene_file(tmp_path):
    """Write a scene text to a file and return its path."""

    def write(text: str, name: str = "scene.toml") -> Path:
        p = tmp_path / name
        p.write_text(text)
        return p

    return write


@pytest.fixture
def quiet():
    """A progress callback that keeps the lines for inspection."""
    lines: list[str] = []
    return lines.append


def edit(text: str, old: str, new: str) -> str:
    """``text`` with its first ``old`` replaced by ``new`` (which must be there: a test edits what it means to)."""
    assert old in text, old
    return text.replace(old, new, 1)
