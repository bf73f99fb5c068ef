"""gmsh geometry builders: one function per geometry family, registered by name.

Every builder takes its parameters as keywords (lengths in m, ``h`` the target element size in m),
writes a MSH 2.2 file (the only version FreeFEM's ``gmshload`` reads) and returns the boundary names
it labelled. Labels come from :mod:`wendel.meshes.labels`.
"""

from .builders import BUILDERS, build, Built
from . import axisymmetric  # noqa: F401  (registers the (r, z) section builders)
from . import cutting  # noqa: F401  (registers the orthogonal-cutting builder)
from . import drilling  # noqa: F401  (registers the drilled-* builders)
from . import cook  # noqa: F401  (registers Cook's membrane)
from . import notched  # noqa: F401  (registers the notched plate)
from .labels import LABELS, NAMES

__all__ = ["BUILDERS", "build", "Built", "LABELS", "NAMES"]
