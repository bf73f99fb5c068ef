"""A plate with a V-notch in its left edge (the separation specimen of ``workflows/dg-separation.toml``).

>>> from meshes.builders import BUILDERS, BOUNDARIES
>>> "notched_plate" in BUILDERS, BOUNDARIES["notched_plate"]()
(True, ['left', 'right', 'bottom', 'top', 'inner'])
"""

from __future__ import annotations

from pathlib import Path

from .builders import Built, _Session, _size_field, _write, register
from .labels import LABELS


@register("notched_plate", ["left", "right", "bottom", "top", "inner"])
def notched_plate(path: Path, width=1.0, height=2.0, notch_depth=0.2, notch_opening=0.1, h=0.1) -> Built:
    """The plate [0, width] x [0, height] (m) with a V-notch of depth ``notch_depth`` and mouth ``notch_opening``
    (m) cut into the left edge at mid-height, its tip at (notch_depth, height / 2). Boundaries: left (both parts),
    right, bottom, top, inner (the two notch flanks)."""
    if not 0 < notch_depth < width or not 0 < notch_opening < height:
        raise ValueError("notched_plate: need 0 < notch_depth < width and 0 < notch_opening < height")
    names = ["left", "right", "bottom", "top", "inner"]
    with _Session("notched_plate") as gmsh:
        occ = gmsh.model.occ
        m, o = height / 2, notch_opening / 2
        xy = [(0, 0), (width, 0), (width, height), (0, height), (0, m + o), (notch_depth, m), (0, m - o)]
        p = [occ.addPoint(x, y, 0) for x, y in xy]
        lines = [occ.addLine(p[i], p[(i + 1) % len(p)]) for i in range(len(p))]
        surf = occ.addPlaneSurface([occ.addCurveLoop(lines)])
        occ.synchronize()
        _size_field(gmsh, h, None)
        groups = {"bottom": [lines[0]], "right": [lines[1]], "top": [lines[2]], "left": [lines[3], lines[6]],
                  "inner": [lines[4], lines[5]]}
        for n in names:
            gmsh.model.addPhysicalGroup(1, groups[n], LABELS[n], n)
        gmsh.model.addPhysicalGroup(2, [surf], LABELS["domain"], "domain")
        return _write(gmsh, path, 2, names)
