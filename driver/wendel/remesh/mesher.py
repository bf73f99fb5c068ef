"""Mesh the deformed configuration of a body anew from its boundary, keeping its named boundaries.

The boundary of the old mesh, moved to the deformed positions, becomes a gmsh model of discrete
entities: one discrete curve (2D) or surface (3D) per connected piece of each boundary label, split at
label changes and at sharp corners (2D). The old physical tags (``meshes/labels.py``) become the physical
groups of the new mesh, which is written as MSH 2.2 (what FreeFEM's ``gmshload``/``gmshload3`` read).

- 2D: the discrete curves get a piecewise-linear parametrization (``createGeometry``) and are meshed
  again with the new size field; a plane surface is built on the curve loops of each body
  (:mod:`wendel.remesh.bodies`; a body cut along the boundary ``opened`` of a DG separation is glued,
  meshed with the cut embedded and cut again there). New boundary nodes lie
  on the old (deformed) boundary polygon, so the domain is preserved exactly wherever the boundary is
  straight between corners, and to O(h^2 curvature) elsewhere.
- 3D: the boundary triangulation is kept as it is (its nodes are the deformed old boundary nodes); the
  volume is meshed again inside it (surface loop + volume, HXT, Netgen optimization). The domain is
  preserved exactly.

The size field is ``h`` where the nodal ``size_indicator`` (plastic strain, contact indicator, ...) is 0
and ``h_min`` where it reaches its maximum, linear in between, given to gmsh as a post-processing
view on the old deformed mesh (background mesh); size ``zones`` (boxes of a finer size, graded to ``h``
outside them, e.g. around a cutting edge) are gmsh Box fields, the smallest size of all holding.

Size: about 430 lines on purpose: one gmsh session per remesh, and the boundary extraction (labelled
facets, chains, loops, shells) feeds both the 2D and the 3D model builder; the pieces have no use apart.
"""

from __future__ import annotations

import time
from collections import defaultdict
from pathlib import Path

import meshio
import numpy as np

from ..meshes import LABELS
from ..meshes.builders import start_gmsh
from ..results import meshfile
from . import bodies, features, quality

OPENED = LABELS["opened"]      # the faces a DG separation opened (separated.msh)

__all__ = ["remesh", "read_mesh", "boundary_facets"]

_VOLUME = {2: "triangle", 3: "tetra"}
_FACET = {2: "line", 3: "triangle"}


def read_mesh(path):
    """Read an MSH 2.2 file: ``(points (n, 3), dim, cells, cell_tags, facets, facet_tags)``.

    ``cells`` are the triangles (2D) or tetrahedra (3D) in file order, ``facets`` the labelled boundary
    lines/triangles, tags are the gmsh physical tags (0 when a block has none).
    """
    m = meshfile.read(path)        # parsed once while the file stays unchanged (shared: copies below)
    dim = 3 if any(c.type == "tetra" for c in m.cells) else 2
    phys = m.cell_data.get("gmsh:physical")

    def gather(kind):
        blocks = [(i, c) for i, c in enumerate(m.cells) if c.type == kind]
        if not blocks:
            return np.zeros((0, dim + (1 if kind == _VOLUME[dim] else 0)), dtype=np.int64), np.zeros(0, dtype=np.int64)
        data = np.concatenate([c.data for _, c in blocks]).astype(np.int64)
        tags = np.concatenate([phys[i] if phys is not None else np.zeros(len(c.data)) for i, c in blocks])
        return data, tags.astype(np.int64)

    cells, cell_tags = gather(_VOLUME[dim])
    facets, facet_tags = gather(_FACET[dim])
    return m.points.copy(), dim, cells, cell_tags, facets, facet_tags


def boundary_facets(cells):
    """Facets (edges of triangles, faces of tetrahedra) that belong to one cell only, oriented outward.

    >>> boundary_facets(np.array([[0, 1, 2], [0, 2, 3]])).tolist()
    [[0, 1], [3, 0], [1, 2], [2, 3]]
    """
    cells = np.asarray(cells)
    if cells.shape[1] == 3:
        local = [(0, 1), (1, 2), (2, 0)]
    else:  # faces opposite vertices 3, 2, 1, 0, outward for positively oriented tetrahedra
        local = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    faces = np.concatenate([cells[:, list(f)] for f in local])
    key = np.sort(faces, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    once = counts[inverse.ravel()] == 1
    out = faces[once]
    order = np.lexsort(np.sort(out, axis=1).T[::-1])
    return out[order]


def _label_facets(bfacets, facets, facet_tags):
    """Physical tag of each boundary facet, from the labelled facets of the file (0 if unlabelled)."""
    table = {tuple(sorted(f)): t for f, t in zip(facets.tolist(), facet_tags.tolist())}
    return np.array([table.get(tuple(sorted(f)), 0) for f in bfacets.tolist()], dtype=np.int64)


def _chains_2d(points, edges, labels, feature_angle, extra_corners=()):
    """Split the boundary edges into chains between corners: ``[(label, [n0, n1, ..., nk]), ...]``.

    Corners are nodes where the label changes, where the boundary is not a simple curve, where the
    boundary turns by more than ``feature_angle`` degrees, and ``extra_corners`` (ends of embedded curves).
    """
    out_edges = defaultdict(list)  # node -> edges leaving it
    in_edges = defaultdict(list)  # node -> edges arriving at it
    for k, (a, b) in enumerate(edges):
        out_edges[a].append(k)
        in_edges[b].append(k)
    corners = set(extra_corners) & (set(out_edges) | set(in_edges))
    cos_max = np.cos(np.radians(feature_angle))
    for n in set(out_edges) | set(in_edges):
        if len(out_edges[n]) != 1 or len(in_edges[n]) != 1:
            corners.add(n)
            continue
        ki, ko = in_edges[n][0], out_edges[n][0]
        if labels[ki] != labels[ko]:
            corners.add(n)
            continue
        t1 = points[n] - points[edges[ki][0]]
        t2 = points[edges[ko][1]] - points[n]
        if np.dot(t1, t2) < cos_max * np.linalg.norm(t1) * np.linalg.norm(t2):
            corners.add(n)
    used = np.zeros(len(edges), dtype=bool)
    chains = []

    def walk(k):
        nodes = [edges[k][0]]
        while True:
            used[k] = True
            b = edges[k][1]
            nodes.append(b)
            if b in corners:
                return nodes
            k = out_edges[b][0]

    for k in range(len(edges)):
        if not used[k] and edges[k][0] in corners:
            chains.append((int(labels[k]), walk(k)))
    for k in range(len(edges)):  # closed loops without any corner: make their first node one
        if not used[k]:
            corners.add(edges[k][0])
            chains.append((int(labels[k]), walk(k)))
    return chains


def _loops(chains):
    """Group chains (oriented head to tail) into closed loops of chain indices."""
    by_start = {}
    for i, (_, nodes) in enumerate(chains):
        by_start.setdefault(nodes[0], []).append(i)
    seen = set()
    loops = []
    for i in range(len(chains)):
        if i in seen:
            continue
        loop, j = [], i
        while j not in seen:
            seen.add(j)
            loop.append(j)
            nxt = [c for c in by_start.get(chains[j][1][-1], []) if c not in seen]
            if not nxt:
                break
            j = nxt[0]
        loops.append(loop)
    return loops


def _shells(faces):
    """Connected components (through shared edges) of boundary faces: a component index per face."""
    return bodies.components(faces)


def _patches(faces, labels):
    """Connected pieces of equally labelled boundary faces: a patch index per face."""
    return bodies.components(faces, labels)


def _size_view(gmsh, points, cells, sizes):
    """A list-based post-processing view of the nodal ``sizes`` on the old deformed mesh."""
    dim = cells.shape[1] - 1
    view = gmsh.view.add("size")
    xyz = points[cells]  # (m, d+1, 3)
    data = np.hstack([xyz[:, :, 0], xyz[:, :, 1], xyz[:, :, 2], sizes[cells]])
    gmsh.view.addListData(view, "ST" if dim == 2 else "SS", len(cells), data.ravel().tolist())
    return view


def _zone_field(gmsh, zone, h):
    """A gmsh Box field: ``zone['h']`` inside ``zone['box'] = [lo, hi]``, growing linearly to ``h`` over
    ``zone['thickness']`` outside it."""
    f = gmsh.model.mesh.field.add("Box")
    lo, hi = (list(c) + [0.0] * (3 - len(c)) for c in zone["box"])
    for key, v in zip(("XMin", "YMin", "ZMin", "XMax", "YMax", "ZMax"), lo + hi):
        gmsh.model.mesh.field.setNumber(f, key, float(v))
    gmsh.model.mesh.field.setNumber(f, "Thickness", float(zone.get("thickness", 0.0)))
    gmsh.model.mesh.field.setNumber(f, "VIn", float(zone["h"]))
    gmsh.model.mesh.field.setNumber(f, "VOut", float(h))
    return f


def remesh(points_deformed, mesh_in_path, out_path, h, size_indicator=None, h_min=None,
           feature_angle=30.0, optimize=True, algorithm_3d=10, zones=None, algorithm_2d=None, smooth_features=0.0,
           trim=None):
    """Mesh the deformed body anew from its boundary; write MSH 2.2 with the same labels.

    Parameters
    ----------
    points_deformed : array_like
        Deformed node coordinates of the mesh in ``mesh_in_path``, in its node order: (n, 2), (n, 3),
        or flat interleaved ``[x0, y0, x1, y1, ...]``. (``X + u`` with ``u`` as FreeFEM writes it.)
    mesh_in_path : path
        The old mesh (MSH 2.2): gives connectivity, boundary labels and the domain label.
    out_path : path
        Where the new mesh is written (MSH 2.2; folders are created).
    h : float
        Target element size (m) where the indicator is 0 (or everywhere without indicator).
    size_indicator : array_like, optional
        Nodal indicator (n,) on the old mesh, e.g. equivalent plastic strain or a contact indicator;
        the size goes linearly from ``h`` (indicator 0) to ``h_min`` (indicator maximum).
    h_min : float, optional
        Smallest size (m); default ``h / 4``.
    zones : list of dict, optional
        Boxes of finer size: ``{"box": [lo, hi], "h": size, "thickness": t}``: ``size`` inside the box,
        growing linearly to ``h`` over the distance ``t`` outside it (gmsh Box fields); with the indicator,
        the smallest of all sizes holds at a point.
    feature_angle : float
        2D: boundary nodes where the boundary turns by more than this (degrees) stay nodes of the new mesh.
    optimize : bool
        3D: Netgen optimization of the tetrahedra (min SICN ~0.3 instead of ~0.005 for raw HXT output).
    algorithm_3d : int
        gmsh ``Mesh.Algorithm3D`` (10 = HXT, 1 = Delaunay).
    algorithm_2d : int, optional
        gmsh ``Mesh.Algorithm`` (default gmsh's 6 = Frontal-Delaunay; 5 = Delaunay, 1 = MeshAdapt).
    smooth_features : float
        2D: old boundary nodes between neighbours closer than the local target size that stand less than this
        share of it off their chord are dropped before meshing (:mod:`wendel.remesh.features`); 0: none.
    trim : dict, optional
        2D: material left out of the new mesh (:func:`trim_cells`: ``point``, ``radius``, ``above``, ``label``,
        the boundary name its cut edges get); the report then has ``trimmed_elements`` and ``trimmed_measure``.

    Returns
    -------
    dict
        ``dimension``, ``nodes``, ``elements``, ``boundary_labels`` (sorted), ``domain_label``,
        ``unlabelled_facets`` (boundary facets of the old mesh without a tag: label 0 in the new mesh),
        ``measure_old``/``measure_new`` (area or volume, m^2/m^3), ``min_sicn``, ``mean_sicn``,
        ``inverted``, ``seconds``, ``path``.
    """
    import gmsh

    t0 = time.perf_counter()
    points0, dim, cells, cell_tags, facets, facet_tags = read_mesh(mesh_in_path)
    n = len(points0)
    pts = np.asarray(points_deformed, dtype=float)
    pts = pts.reshape(n, -1) if pts.ndim == 1 else pts
    pts = np.hstack([pts[:, :dim], np.zeros((n, 3 - dim))]) if dim == 2 or pts.shape[1] < 3 else pts[:, :3].copy()
    domain_labels = np.unique(cell_tags)
    if len(domain_labels) != 1:
        raise ValueError(f"{mesh_in_path}: remesh supports one domain label, found {domain_labels.tolist()}")
    domain_label = int(domain_labels[0])
    meas_old = quality.signed_measure(pts, cells)
    if np.any(meas_old <= 0):
        raise ValueError(f"deformed mesh has {np.count_nonzero(meas_old <= 0)} inverted elements: "
                         "remesh from an earlier increment")
    cut = None
    if dim == 2 and OPENED in facet_tags:       # cut along opened faces: glued, meshed with the cut embedded
        rep, cut = bodies.glue(points0, cells, facets, facet_tags, OPENED)
        inside = {tuple(e) for e in cut.tolist()}
        keep = np.array([not (t == OPENED and tuple(sorted(f)) in inside)
                         for f, t in zip(rep[facets].tolist(), facet_tags.tolist())], dtype=bool)
        facets, facet_tags, cells = rep[facets[keep]], facet_tags[keep], rep[cells]
        pts = _mean_of_copies(pts, rep)
        if np.any(quality.signed_measure(pts, cells) <= 0):
            raise ValueError(f"{mesh_in_path}: the faces cut along '{OPENED}' have opened so far that the mesh "
                             "glued at their mean position inverts: remesh from an earlier increment")
    trimmed = (0, 0.0)
    if trim is not None and (dim != 2 or cut is not None):
        raise ValueError("remesh.trim is for 2D bodies without opened faces")
    if trim is not None:
        keep = trim_cells(pts, cells, trim["point"], trim["radius"], trim["above"])
        if not keep.all():
            names = meshfile.read(mesh_in_path).field_data
            if trim["label"] not in names:
                raise ValueError(f"{mesh_in_path}: remesh.trim.label = {trim['label']!r} is none of the mesh's "
                                 f"names ({', '.join(sorted(names))})")
            trimmed = (int((~keep).sum()), float(meas_old[~keep].sum()))
            cells = cells[keep]
    bf = boundary_facets(cells)
    if trimmed[0]:      # the cut's edges (boundary now, no old facet) get the trim's label
        old = {tuple(sorted(f)) for f in facets.tolist()}
        inner = np.array([f for f in bf.tolist() if tuple(sorted(f)) not in old], dtype=facets.dtype).reshape(-1, 2)
        facets = np.vstack([facets, inner])
        facet_tags = np.concatenate([facet_tags, np.full(len(inner), int(names[trim["label"]][0]))])
    labels = _label_facets(bf, facets, facet_tags)
    h_min = h / 4 if h_min is None else h_min
    smoothed = 0
    if dim == 2 and smooth_features > 0 and cut is None:    # sub-resolution wrinkles of the boundary
        size = features.target_size(pts, h, size_indicator, h_min, zones)
        n_edges = len(bf)
        bf, labels = features.smooth(pts, bf, labels, size, smooth_features)
        smoothed = n_edges - len(bf)

    start_gmsh()          # keeps the driver's Ctrl-C and SIGTERM handlers
    try:
        gmsh.model.add("remesh")
        groups = defaultdict(list)
        if dim == 2:     # one plane surface per body (several bodies, bodies cut along opened faces)
            entities = bodies.model_2d(gmsh, pts, cells, bf, labels, feature_angle, groups, _chains_2d, _loops,
                                       cut, OPENED)
        else:
            entities = [_model_3d(gmsh, pts, bf, labels, groups)]
        for lab, tags in sorted(groups.items()):
            g = gmsh.model.addPhysicalGroup(dim - 1, tags, lab)
            gmsh.model.setPhysicalName(dim - 1, g, _name(lab))
        g = gmsh.model.addPhysicalGroup(dim, entities, domain_label)
        gmsh.model.setPhysicalName(dim, g, _name(domain_label))

        if size_indicator is None and not zones:
            gmsh.option.setNumber("Mesh.MeshSizeMin", h)
            gmsh.option.setNumber("Mesh.MeshSizeMax", h)
        else:
            fields, smallest = [], h
            if size_indicator is not None:
                view = _size_view(gmsh, pts, cells, features.indicator_size(h, h_min, size_indicator, n))
                f = gmsh.model.mesh.field.add("PostView")
                gmsh.model.mesh.field.setNumber(f, "ViewTag", view)
                fields.append(f)
                smallest = h_min
            for z in zones or []:
                fields.append(_zone_field(gmsh, z, h))
                smallest = min(smallest, z["h"])
            f = fields[0]
            if len(fields) > 1:
                f = gmsh.model.mesh.field.add("Min")
                gmsh.model.mesh.field.setNumbers(f, "FieldsList", fields)
            gmsh.model.mesh.field.setAsBackgroundMesh(f)
            gmsh.option.setNumber("Mesh.MeshSizeMin", smallest)
            gmsh.option.setNumber("Mesh.MeshSizeMax", h)
            gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
            gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
            gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)
        if dim == 2 and algorithm_2d is not None:
            gmsh.option.setNumber("Mesh.Algorithm", algorithm_2d)
        if dim == 3:
            gmsh.option.setNumber("Mesh.Algorithm3D", algorithm_3d)
            gmsh.option.setNumber("Mesh.OptimizeNetgen", 1 if optimize else 0)
        gmsh.model.mesh.generate(dim)

        tags, x, _ = gmsh.model.mesh.getNodes()
        x = x.reshape(-1, 3)
        index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
        index[tags] = np.arange(len(tags))
        etype = 2 if dim == 2 else 4
        _, conn = gmsh.model.mesh.getElementsByType(etype)
        new_cells = index[conn.astype(np.int64)].reshape(-1, dim + 1)
        if len(new_cells) == 0:
            raise ValueError(f"{mesh_in_path}: gmsh made no {_VOLUME[dim]}s from its boundary (see gmsh's log)")
        q = quality.mesh_quality(x, new_cells)

        gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        out_path = Path(out_path)
        out_path.parent.mkdir(parents=True, exist_ok=True)
        gmsh.write(str(out_path))
    finally:
        gmsh.finalize()
    if cut is not None:     # open the new mesh along the embedded curves again
        from ..results.separation import reopen
        x, new_cells = reopen(out_path)
    return {
        "path": out_path,
        "dimension": dim,
        "nodes": len(x),
        "elements": len(new_cells),
        "bodies": int(bodies.body_index(new_cells).max()) + 1 if dim == 2 else 1,
        "boundary_labels": sorted(int(k) for k in groups),
        "domain_label": domain_label,
        "unlabelled_facets": int(np.count_nonzero(labels == 0)),
        "boundary_nodes_smoothed": int(smoothed),
        "measure_old": float(meas_old.sum()),
        "measure_new": float(quality.signed_measure(x, new_cells).sum()),
        "min_sicn": q["min"],
        "mean_sicn": q["mean"],
        "inverted": q["inverted"],
        "seconds": time.perf_counter() - t0,
        **({"trimmed_elements": trimmed[0], "trimmed_measure": trimmed[1]} if trim is not None else {}),
    }


def trim_cells(points, cells, point, radius: float, above: float) -> np.ndarray:
    """Which 2D ``cells`` (triangles of ``points``) a trimmed mesh keeps: not those whose centre lies farther
    than ``radius`` from ``point`` and above ``above`` (y), and of the rest only the largest body (cells joined by
    edges, by area): a piece the cut leaves hanging goes too.

    >>> pts = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.0, 2.0], [1.0, 2.0], [0.0, 3.0]])
    >>> tri = np.array([[0, 1, 2], [0, 2, 3], [3, 2, 5], [3, 5, 4], [4, 5, 6]])
    >>> trim_cells(pts, tri, [0.5, 0.0], 1.6, 0.5).tolist()       # the top two go: far and above 0.5
    [True, True, True, False, False]
    >>> trim_cells(pts, tri, [0.5, 0.0], 1.6, 5.0).tolist()       # nothing above 5
    [True, True, True, True, True]
    """
    p = np.asarray(points, dtype=float)[:, :2]
    c = p[cells].mean(axis=1)
    out = (np.hypot(c[:, 0] - point[0], c[:, 1] - point[1]) > radius) & (c[:, 1] > above)
    keep = ~out
    if not out.any() or not keep.any():
        return keep
    kept = np.flatnonzero(keep)
    body = bodies.body_index(cells[kept])
    area = np.abs(quality.signed_measure(p, cells[kept]))
    largest = np.argmax(np.bincount(body, weights=area))
    keep[kept[body != largest]] = False
    return keep


def _mean_of_copies(pts, rep):
    """Every vertex at the mean position of the copies merged into its representative ``rep``."""
    out = pts.copy()
    total = np.zeros_like(pts)
    np.add.at(total, rep, pts)
    count = np.bincount(rep, minlength=len(pts)).astype(float)
    merged = count > 1
    out[merged] = total[merged] / count[merged, None]
    return out


def _name(label):
    try:
        from ..meshes.labels import NAMES
    except ImportError:  # running from a checkout without the package mapping
        try:
            from meshes.labels import NAMES
        except ImportError:
            NAMES = {}
    return NAMES.get(label, f"label{label}")


def _model_3d(gmsh, pts, faces, labels, groups):
    """Discrete surfaces (one per connected patch of a label) with the old triangulation; one volume."""
    patch = _patches(faces, labels)
    shell = _shells(faces)
    nodes_done = np.zeros(len(pts), dtype=bool)
    shell_surfaces = defaultdict(list)
    shell_extent = {}
    for p in range(patch.max() + 1):
        sel = patch == p
        tag = p + 1
        gmsh.model.addDiscreteEntity(2, tag)
        tri = faces[sel]
        nodes = np.unique(tri)
        nodes = nodes[~nodes_done[nodes]]
        nodes_done[nodes] = True
        if len(nodes):
            gmsh.model.mesh.addNodes(2, tag, (nodes + 1).tolist(), pts[nodes].ravel().tolist())
        gmsh.model.mesh.addElementsByType(tag, 2, [], (tri + 1).ravel().tolist())
        groups[int(labels[sel][0])].append(tag)
        s = int(shell[sel][0])
        shell_surfaces[s].append(tag)
        ext = np.ptp(pts[np.unique(faces[shell == s])], axis=0)
        shell_extent[s] = float(np.prod(ext))
    order = sorted(shell_surfaces, key=lambda s: -shell_extent[s])  # outer shell first, then cavities
    loops = [gmsh.model.geo.addSurfaceLoop(shell_surfaces[s]) for s in order]
    volume = gmsh.model.geo.addVolume(loops)
    gmsh.model.geo.synchronize()
    return volume
