"""Registry of optional physics blocks (``[plasticity]``, ``[contact]``, ``[thermal]`` in a scene).

A block module in this package calls :func:`register` with a :class:`Block`: the scene table's
pydantic model, the function that turns the validated table into FreeFEM ``-key value`` options, and
the FreeFEM macro that switches its module on. A scene composes only the blocks it names; each adds
``-D<macro>=1`` to the launch of ``edp/mechanics.edp`` (``-DWITHPLASTICITY=1``), so FreeFEM compiles
only those modules (``IFMACRO(WITHPLASTICITY)`` in ``edp/lib/mechanics.idp``).

>>> sorted(BLOCKS) == sorted(set(BLOCKS))
True
"""

from __future__ import annotations

import dataclasses
import importlib
import pkgutil
from typing import Any, Callable, Optional

from pydantic import AfterValidator, BaseModel
from typing_extensions import Annotated


def choice(registry, what: str):
    """A string type whose value must be a key of ``registry``; the error lists the valid names.

    >>> from pydantic import TypeAdapter
    >>> TypeAdapter(choice({"ball": 1}, "obstacle")).validate_python("ball")
    'ball'
    """

    def check(v: str) -> str:
        if v not in registry:
            raise ValueError(f"unknown {what} {v!r}; valid: {', '.join(registry)}")
        return v

    return Annotated[str, AfterValidator(check)]


@dataclasses.dataclass(frozen=True)
class Block:
    """One optional physics block.

    Attributes
    ----------
    name : str
        Table name in the scene file.
    model : type[BaseModel]
        Schema of the table (every key with type, default, unit and range in its Field).
    options : callable
        ``options(block, scene, files) -> list[str]``: FreeFEM options (numbers and integer ids only);
        ``files`` is a :class:`wendel.loop.checkpoint.RunFiles` where a block may write tables it needs.
    fields : tuple of str
        Names of the VTU fields the module writes (documentation and tests).
    mechanics : bool
        True for a module of the mechanics entry scripts; False for the table of a scalar problem
        (see :class:`Problem`), which mechanics scenes refuse.
    check : callable or None
        ``check(block, scene)``: rules that join this table with others, applied when the scene is read
        (``wendel check``); raises ValueError naming the keys.
    macro : str or None
        The FreeFEM macro the block's module is compiled under: a scene naming the block launches
        ``edp/mechanics.edp`` with ``-D<macro>=1`` (``WITHPLASTICITY``); None: the block compiles no code
        of its own (a table of a scalar problem).
    """

    name: str
    model: type[BaseModel]
    options: Callable[[Any, Any, Any], list[str]]
    fields: tuple[str, ...] = ()
    mechanics: bool = True
    check: Optional[Callable[[Any, Any], None]] = None
    macro: Optional[str] = None


BLOCKS: dict[str, Block] = {}


def register(block: Block) -> Block:
    """Add ``block`` to the registry (called at import time by each block module)."""
    BLOCKS[block.name] = block
    return block


@dataclasses.dataclass(frozen=True)
class Problem:
    """A problem other than the default quasi-static mechanics (a scene's top-level ``problem`` key).

    Attributes
    ----------
    name : str
        Value of ``problem`` in the scene.
    entry : callable
        ``entry(scene, dimension) -> str``: the entry script in edp/.
    options : callable
        ``options(scene, files, dimension) -> list[str]``: its FreeFEM options besides the common ones
        (-mesh, -loads, -inc0, -restart, -solver*, -newton_*).
    tables : tuple of str
        The top-level tables (blocks) the problem reads, e.g. ``("obstacle",)``; the mechanics tables
        (material, elasticity, boundary, body_force) are refused for it unless listed.
    macros : tuple of str
        FreeFEM macros its entry script is launched with (``-D<name>=1`` each); none today.
    """

    name: str
    entry: Callable[[Any, int], str]
    options: Callable[[Any, Any, int], list[str]]
    tables: tuple[str, ...] = ()
    macros: tuple[str, ...] = ()


PROBLEMS: dict[str, Problem] = {}


def register_problem(problem: Problem) -> Problem:
    """Add ``problem`` to the registry."""
    PROBLEMS[problem.name] = problem
    return problem


def load_all() -> dict[str, Block]:
    """Import every block module of this package (each registers itself) and return the registry."""
    for info in pkgutil.iter_modules(__path__):
        importlib.import_module(f"{__name__}.{info.name}")
    # one order whatever imported a block first (the scene model, its key table and the README follow it)
    for registry in (BLOCKS, PROBLEMS):
        items = sorted(registry.items())
        registry.clear()
        registry.update(items)
    return BLOCKS
