"""Cook's membrane (Cook 1974): the tapered panel with corners (0, 0), (48, 44), (48, 60), (0, 44), clamped on
the left edge and sheared on the right one; the locking benchmark of ``workflows/cook-*.toml``.

>>> from meshes.builders import BUILDERS, BOUNDARIES
>>> "cook_membrane" in BUILDERS, BOUNDARIES["cook_membrane"]()
(True, ['left', 'right', 'bottom', 'top'])
"""

from __future__ import annotations

from pathlib import Path

from .builders import Built, _Session, _size_field, _write, register
from .labels import LABELS

CORNERS = ((0.0, 0.0), (48.0, 44.0), (48.0, 60.0), (0.0, 44.0))
"""The panel's corners [m] (the benchmark's lengths, read in m)."""


@register("cook_membrane", ["left", "right", "bottom", "top"])
def cook_membrane(path: Path, h=4.0, divisions=0) -> Built:
    """Cook's panel: boundaries left (x = 0, 44 long), right (x = 48, 16 long), bottom and top (slanted).

    ``divisions`` > 0: a structured mesh of divisions x divisions quadrilaterals, each cut into two triangles
    (the benchmark's n x n meshes); 0: unstructured triangles of size ``h`` [m].
    """
    names = ["left", "right", "bottom", "top"]
    with _Session("cook_membrane") as gmsh:
        occ = gmsh.model.occ
        p = [occ.addPoint(x, y, 0) for x, y in CORNERS]
        lines = {"bottom": occ.addLine(p[0], p[1]), "right": occ.addLine(p[1], p[2]),
                 "top": occ.addLine(p[2], p[3]), "left": occ.addLine(p[3], p[0])}
        surf = occ.addPlaneSurface([occ.addCurveLoop([lines[n] for n in ("bottom", "right", "top", "left")])])
        occ.synchronize()
        if divisions > 0:
            for n in names:
                gmsh.model.mesh.setTransfiniteCurve(lines[n], int(divisions) + 1)
            gmsh.model.mesh.setTransfiniteSurface(surf)
        else:
            _size_field(gmsh, h, None)
        for n in names:
            gmsh.model.addPhysicalGroup(1, [lines[n]], LABELS[n], n)
        gmsh.model.addPhysicalGroup(2, [surf], LABELS["domain"], "domain")
        return _write(gmsh, path, 2, names)
