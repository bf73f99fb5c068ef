"""Content-addressed cache of built meshes, opt-in: ``WENDEL_MESH_CACHE=DIR`` (or ``--mesh-cache DIR``).

Campaigns, studies and benches mesh the same geometry again and again; gmsh is half of the 3D ball's run.
With the variable set, :func:`wendel.meshes.build` looks up a key, the sha256 over

- the builder's name and its parameters (sorted JSON; floats by ``repr``, so 0.1 and 0.1000001 differ),
- the gmsh version,
- the source of this package (every ``*.py`` of ``meshes/``: a change of any builder misses the cache).

An entry is a folder ``DIR/<key>/`` with ``mesh.msh`` and ``meta.json`` (the :class:`Built` fields and the
sha256 of the mesh). A hit copies the mesh into place after checking its sha256; a corrupt entry is rebuilt
with a warning, never used. A miss builds into place and stores the entry atomically: the folder is written
under a temporary name in DIR and renamed, so two processes building one key at once leave one valid
entry (the loser's rename fails and its copy is dropped). ``<mesh>.cache.json`` next to the mesh says hit or
miss and the key (summary.json's ``mesh_cache``). Without the variable nothing changes.

>>> len(key("box", {"h": 0.1, "lengths": (1, 2)})) == 64
True
>>> key("box", {"h": 0.1}) != key("box", {"h": 0.1000001})
True
>>> key("box", {"a": 1, "b": 2.0}) == key("box", {"b": 2.0, "a": 1})
True
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import shutil
import tempfile
import warnings
from pathlib import Path

ENV = "WENDEL_MESH_CACHE"


def _plain(value):
    """JSON for what json does not know (tuples are lists already; paths, numpy scalars)."""
    if isinstance(value, Path):
        return str(value)
    if hasattr(value, "item"):           # numpy scalar
        return value.item()
    if hasattr(value, "tolist"):         # numpy array
        return value.tolist()
    raise TypeError(f"mesh cache: cannot key a parameter of type {type(value).__name__}")


@functools.lru_cache(maxsize=1)
def source_hash() -> str:
    """sha256 over the names and bytes of this package's Python files."""
    h = hashlib.sha256()
    for f in sorted(Path(__file__).parent.glob("*.py")):
        h.update(f.name.encode() + b"\0" + f.read_bytes() + b"\0")
    return h.hexdigest()


@functools.lru_cache(maxsize=1)
def gmsh_version() -> str:
    import gmsh

    return str(gmsh.__version__)


def key(name: str, params: dict) -> str:
    """The cache key of builder ``name`` with keywords ``params``."""
    text = json.dumps({"builder": name, "params": params, "gmsh": gmsh_version(), "source": source_hash()},
                      sort_keys=True, default=_plain)       # json writes floats by repr
    return hashlib.sha256(text.encode()).hexdigest()


def _digest(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _lookup(entry: Path):
    """(meta, mesh bytes) of a valid entry, None if there is none; a corrupt one is moved aside."""
    meta_file = entry / "meta.json"
    if not meta_file.is_file():
        return None
    try:
        meta = json.loads(meta_file.read_text())
        data = (entry / "mesh.msh").read_bytes()
        if _digest(data) == meta["sha256"]:
            return meta, data
        why = "sha256 mismatch"
    except (OSError, ValueError, KeyError) as e:
        why = f"{type(e).__name__}: {e}"
    warnings.warn(f"mesh cache: corrupt entry {entry} ({why}); rebuilding it", RuntimeWarning, stacklevel=3)
    _discard(entry)
    return None


def _discard(entry: Path) -> None:
    """Remove an entry folder (renamed first, so no reader sees it half-deleted)."""
    aside = entry.parent / f".bad-{entry.name}-{os.getpid()}"
    try:
        os.rename(entry, aside)
    except OSError:
        return                                  # another process moved or replaced it already
    shutil.rmtree(aside, ignore_errors=True)


def _store(entry: Path, mesh: Path, meta: dict) -> None:
    tmp = Path(tempfile.mkdtemp(prefix=f".tmp-{entry.name[:12]}-", dir=entry.parent))
    try:
        shutil.copyfile(mesh, tmp / "mesh.msh")
        (tmp / "meta.json").write_text(json.dumps(meta, indent=1, default=_plain))
        os.rename(tmp, entry)                   # atomic; fails if another process stored the key first
    except OSError:
        pass
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def build(name: str, path: Path, params: dict, make):
    """``make(path, **params)`` through the cache in ``$WENDEL_MESH_CACHE`` (straight through without it)."""
    root = os.environ.get(ENV)
    if not root:
        return make(path, **params)
    from .builders import Built

    root = Path(root)
    root.mkdir(parents=True, exist_ok=True)
    k = key(name, params)
    entry = root / k
    found = _lookup(entry)
    if found is not None:
        meta, data = found
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        if _digest(path.read_bytes()) != meta["sha256"]:
            raise OSError(f"mesh cache: copy of {entry / 'mesh.msh'} to {path} differs from the entry")
        return _record(Built(path, meta["dimension"], list(meta["boundaries"]), meta["nodes"], meta["elements"]),
                       root, k, True)
    built = make(path, **params)
    meta = {"builder": name, "params": params, "gmsh": gmsh_version(), "source": source_hash(),
            "sha256": _digest(Path(built.path).read_bytes()), "dimension": built.dimension,
            "boundaries": list(built.boundaries), "nodes": built.nodes, "elements": built.elements}
    _store(entry, Path(built.path), meta)
    return _record(built, root, k, False)


def _record(built, root: Path, k: str, hit: bool):
    """Say where the mesh came from: in ``built.cache`` and in ``<mesh>.cache.json`` next to the mesh (a run's
    summary.json reads it)."""
    built.cache = {"dir": str(root), "key": k, "hit": hit}
    sidecar(Path(built.path)).write_text(json.dumps(built.cache))
    return built


def sidecar(mesh: Path) -> Path:
    """The file next to ``mesh`` that says whether it came from the cache."""
    return mesh.with_name(mesh.name + ".cache.json")
