"""The orthogonal-cutting workpiece (plane strain): a block with the layer to be cut on top.

The tool moves in -x. The machined level is y = 0; the layer 0 <= y <= uncut is the uncut chip. At the
right end a step of length ``pre_cut`` is already machined, so the tool starts against the step face::

    y = uncut  +-------------------------------+              free_surface (top and step face)
     layer_end |            cut layer          |
    y = 0      +                               +-------+     machined (y = 0, x >= length - pre_cut)
          left |                                       |     right
    y = -depth +---------------------------------------+     bottom
              x = 0                                 x = length

The left end is split at the machined level: ``left`` below it (where a scene holds the workpiece),
``layer_end`` for the cut layer, so that no node of ``left`` is on ``free_surface`` (the contact surface of
the FE cut, whose nodes must have every component free).

Elements have size ``h``, graded down to ``fine * h`` in a band along the tool path (the cut layer and
``band`` uncut chip thicknesses below the machined level, where the primary shear zone and the machined
surface form); both are ratios, so the band follows ``h`` in studies and smoke runs.

>>> import tempfile, pathlib
>>> b = orthogonal_cutting(pathlib.Path(tempfile.mkdtemp()) / "w.msh", h=1e-4, fine=0.5)
>>> b.boundaries
['left', 'bottom', 'right', 'machined', 'free_surface', 'layer_end']
"""

from __future__ import annotations

from pathlib import Path

from .builders import Built, _Session, _size_field, _write, register
from .labels import LABELS


@register("orthogonal-cutting", ["left", "bottom", "right", "machined", "free_surface", "layer_end"])
def orthogonal_cutting(path: Path, length=2e-3, depth=1e-3, uncut=0.15e-3, pre_cut=0.3e-3, band=2.0,
                       fine=0.25, h=1e-4, refine=None) -> Built:
    """Workpiece of an orthogonal cut (lengths in m): ``length`` along the cut, ``depth`` below the
    machined level, the cut layer ``uncut`` thick, a machined step ``pre_cut`` long at the right end;
    size ``h``, and ``fine * h`` in the band from ``band * uncut`` below the machined level to the top of
    the cut layer; ``refine`` (a zone of the builders, e.g. around the tool's edge at the step face) finer
    still where it asks a smaller size."""
    h_fine, band = fine * h, band * uncut
    if not (0 < pre_cut < length and 0 < uncut and 0 < depth and 0 < band <= depth and 0 < fine <= 1):
        raise ValueError("orthogonal-cutting needs 0 < pre_cut < length, uncut > 0, 0 < band * uncut <= depth "
                         "and 0 < fine <= 1")
    x_step = length - pre_cut
    with _Session("orthogonal-cutting") as gmsh:
        geo = gmsh.model.geo
        corners = [(0.0, -depth), (length, -depth), (length, 0.0), (x_step, 0.0), (x_step, uncut), (0.0, uncut),
                   (0.0, 0.0)]
        pts = [geo.addPoint(x, y, 0.0) for x, y in corners]
        lines = [geo.addLine(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]
        loop = geo.addCurveLoop(lines)
        surface = geo.addPlaneSurface([loop])
        geo.synchronize()
        bottom, right, machined, step, top, layer_end, left = lines
        groups = {"left": [left], "bottom": [bottom], "right": [right], "machined": [machined],
                  "free_surface": [step, top], "layer_end": [layer_end]}
        for name, tags in groups.items():
            gmsh.model.addPhysicalGroup(1, tags, LABELS[name], name)
        gmsh.model.addPhysicalGroup(2, [surface], LABELS["domain"], "domain")
        # the refined band along the tool path: a block zone of the builders' size field
        band_zone = {"box": [[-h, -band], [length + h, uncut + h]], "h": h_fine, "thickness": band}
        if not refine:
            _size_field(gmsh, h, band_zone)
        else:       # the smaller of the band's and the zone's sizes (the builders' size field, each on its own)
            f = gmsh.model.mesh.field
            fields = []
            for zone in (band_zone, refine):
                _size_field(gmsh, h, zone)
                fields.append(max(f.list()))
            both = f.add("Min")
            f.setNumbers(both, "FieldsList", fields)
            f.setAsBackgroundMesh(both)
        return _write(gmsh, path, 2, list(groups))
