"""A seeded fuzzer of scene files: every scene in workflows/, mutated as a clumsy or hostile user would.

Each mutation changes one key or table (wrong type, non-finite or overflowing number, boolean or string for a
number, out-of-range value, unknown key, missing table, path-like or control-character strings) and runs
``wendel check`` on it in-process. Asserted for every mutation:

- the exit code is 0 or 2 and no exception escapes (a traceback is a failure);
- exit 2 prints a message that names the scene file and the mutated key (its last dotted part);
- a number replaced by a non-finite value, a boolean or a string is refused (exit 2).

The count of mutations run is printed (``pytest -s``) and asserted to be at least ``MIN_MUTATIONS``.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import random
import zlib
import tomllib
from pathlib import Path

import pytest
import tomli_w

from wendel.cli import main

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "workflows").glob("*.toml"))
PER_SCENE = int(os.environ.get("WENDEL_FUZZ_PER_SCENE", 60))
MIN_MUTATIONS = 1000
SEED = int(os.environ.get("WENDEL_FUZZ_SEED", 20261122))   # each scene draws from SEED and its own name

NOT_NUMBERS = [math.inf, -math.inf, math.nan, True, False, "1.0", "abc", [], {}]
ODD_VALUES = [0, -1, -1e-300, 1.7e308, -1.7e308, 10**30, 1e-300, "", "../../etc/passwd", "\x1b[2J\x07ding",
              "Error line number 1, in file /etc/shadow", [1.0, math.nan], [math.inf], {"x": 1}]


def _leaves(data, prefix=()):
    """Every (path, value) below ``data``: tables and values alike."""
    for key, value in data.items():
        path = prefix + (key,)
        yield path, value
        if isinstance(value, dict):
            yield from _leaves(value, path)


def _set(data, path, value):
    node = data
    for key in path[:-1]:
        node = node[key]
    if value is _DELETE:
        del node[path[-1]]
    else:
        node[path[-1]] = value


_DELETE = object()


def mutations(text: str, rng: random.Random, count: int):
    """``count`` (description, mutated dict, path, must_refuse) of the scene ``text``."""
    base = tomllib.loads(text)
    paths = [(p, v) for p, v in _leaves(base)]
    for _ in range(count):
        data = tomllib.loads(text)
        path, value = rng.choice(paths)
        kind = rng.choice(["not-number", "odd", "delete", "unknown-key", "table-to-scalar"])
        must_refuse = False
        if kind == "not-number":
            new = rng.choice(NOT_NUMBERS)
            must_refuse = isinstance(value, (int, float)) and not isinstance(value, bool)
        elif kind == "odd":
            new = rng.choice(ODD_VALUES)
        elif kind == "delete":
            new = _DELETE
        elif kind == "unknown-key":
            if isinstance(value, dict):
                path, new, must_refuse = path + ("no_such_key",), 1.0, True
            else:
                path, new, must_refuse = path[:-1] + (path[-1] + "_typo",), value, True
        else:
            new = rng.choice([1.0, "x", True])
            must_refuse = isinstance(value, dict)
        try:
            _set(data, path, new)
        except (KeyError, TypeError):
            continue
        yield f"{'.'.join(map(str, path))} <- {kind} {new if new is not _DELETE else 'deleted'!r}", data, path, must_refuse


def _check(path: Path) -> tuple[int, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(["check", str(path)])
    return code, out.getvalue() + err.getvalue()


def test_fuzzed_scenes_are_refused_clearly(tmp_path):
    ran, refused, failures = 0, 0, []
    for scene in SCENES:
        rng = random.Random(SEED * 1_000_003 + zlib.crc32(scene.name.encode()))   # new scenes change no others
        text = scene.read_text()
        for i, (what, data, path, must_refuse) in enumerate(mutations(text, rng, PER_SCENE)):
            f = tmp_path / f"{scene.stem}-{i}.toml"
            try:
                f.write_text(tomli_w.dumps(data))
            except (TypeError, ValueError):
                continue            # a value TOML cannot hold (never reaches wendel)
            for image in (scene.parent / "images").glob("*"):      # scenes may name images next to them
                (tmp_path / "images").mkdir(exist_ok=True)
                target = tmp_path / "images" / image.name
                if not target.exists():
                    target.write_bytes(image.read_bytes())
            ran += 1
            try:
                code, message = _check(f)
            except SystemExit as exc:     # argparse only; never expected here
                failures.append(f"{scene.name}: {what}: SystemExit {exc.code}")
                continue
            except Exception as exc:      # a traceback for the user
                failures.append(f"{scene.name}: {what}: {type(exc).__name__}: {exc}")
                continue
            if code not in (0, 2):
                failures.append(f"{scene.name}: {what}: exit {code}: {message.strip()[:200]}")
            elif code == 2:
                refused += 1
                key = str(path[-1])
                if str(f) not in message or key not in message:
                    failures.append(f"{scene.name}: {what}: message does not name the file and {key!r}: "
                                    f"{message.strip()[:300]}")
                if any(ord(c) < 32 and c not in "\n\t" for c in message):
                    failures.append(f"{scene.name}: {what}: raw control characters printed")
            elif must_refuse:
                failures.append(f"{scene.name}: {what}: accepted")
    print(f"\nfuzz: {ran} mutations of {len(SCENES)} scenes, {refused} refused, {len(failures)} failures")
    assert ran >= min(MIN_MUTATIONS, PER_SCENE * len(SCENES) * 9 // 10)
    assert not failures, f"{len(failures)} of {ran} mutations handled badly:\n" + "\n".join(failures[:60])
