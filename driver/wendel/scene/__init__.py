"""A scene: its schema (every key once), its optional physics blocks, reading and validating a file.

:func:`load` reads a scene file; :mod:`.schema` holds the keys; :mod:`.blocks` the optional blocks
(``[plasticity]``, ``[contact]``, ``[thermal]``, ...) and the problems other than mechanics.
"""

from .reading import SceneError, apply_smoke, load, parse

__all__ = ["SceneError", "apply_smoke", "load", "parse"]
