"""The cutting tool of an orthogonal cut as a polygon: rake face, rounded edge of radius r, flank face.

The tool moves in -x; the chip flows up its rake face (its left side), the machined surface passes
under its flank face (its bottom side). Angles follow the usual convention:

* rake angle ``alpha``: between the rake face and the normal to the cutting direction (the y axis),
  positive when the face leans back, away from the chip: the rake face runs along ``(sin a, cos a)``;
* clearance angle ``gamma``: between the flank face and the cutting direction: the flank face runs
  along ``(cos g, sin g)`` from the edge;
* the wedge angle between them is ``90 deg - alpha - gamma``.

The edge is an arc of radius ``r`` tangent to both faces; its lowest point is the ``tip`` (the tool's
reference point, put at the machined level y = 0). Vertices are in metres and counter-clockwise (the
tool on the left of each edge), the form the polygon tool of the contact module takes.

>>> t = tool_polygon(rake=math.radians(-7), clearance=math.radians(5), edge_radius=20e-6,
...                  rake_length=1e-3, flank_length=0.6e-3)
>>> t.vertices.shape[1], t.signed_area() > 0
(2, True)
>>> [round(math.degrees(a), 6) for a in t.face_angles()]
[-7.0, 5.0]
>>> float(round(t.vertices[:, 1].min(), 15))     # the tip is the lowest point
0.0
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np


@dataclasses.dataclass
class ToolPolygon:
    """A closed counter-clockwise polygon (the last vertex joins the first) and how it was built."""

    vertices: np.ndarray          # (n, 2), m
    rake: float                   # rad
    clearance: float              # rad
    edge_radius: float            # m
    edge_center: np.ndarray       # (2,), m
    rake_segment: tuple[int, int]   # vertex indices of the rake face (top -> edge)
    flank_segment: tuple[int, int]  # vertex indices of the flank face (edge -> back)
    arc: tuple[int, int]            # first and last vertex index of the edge arc

    def signed_area(self) -> float:
        """Shoelace area [m^2]: positive for counter-clockwise vertices."""
        x, y = self.vertices[:, 0], self.vertices[:, 1]
        return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))

    def face_angles(self) -> tuple[float, float]:
        """(rake angle, clearance angle) [rad] measured from the rake and flank segments."""
        a, b = self.vertices[self.rake_segment[0]], self.vertices[self.rake_segment[1]]
        down = b - a                                  # along the rake face, towards the edge
        rake = math.atan2(-down[0], -down[1])         # angle of (a - b) from +y, positive towards +x
        c, d = self.vertices[self.flank_segment[0]], self.vertices[self.flank_segment[1]]
        along = d - c
        return rake, math.atan2(along[1], along[0])

    def moved(self, dx: float, dy: float = 0.0) -> "ToolPolygon":
        """The tool translated by (dx, dy) [m] (its path: dx = -V t)."""
        return dataclasses.replace(self, vertices=self.vertices + [dx, dy], edge_center=self.edge_center + [dx, dy])

    def write(self, path: Path) -> Path:
        """Plain text for FreeFEM: the vertex count, then one ``x y`` row per vertex (m)."""
        path = Path(path)
        path.write_text(f"{len(self.vertices)}\n" + "".join(f"{float(x)!r} {float(y)!r}\n" for x, y in self.vertices))
        return path

    def to_json(self) -> str:
        return json.dumps({"vertices_m": self.vertices.tolist(), "rake_deg": math.degrees(self.rake),
                           "clearance_deg": math.degrees(self.clearance), "edge_radius_m": self.edge_radius,
                           "edge_center_m": self.edge_center.tolist(), "counter_clockwise": True})


def tool_polygon(rake: float, clearance: float, edge_radius: float, rake_length: float, flank_length: float,
                 tip: tuple[float, float] = (0.0, 0.0), arc_segments: int | None = None) -> ToolPolygon:
    """The tool polygon (angles in rad, lengths in m); ``arc_segments`` straight pieces on the edge arc
    (default: one per 5 deg of arc, at least 4); ``edge_radius = 0`` gives a sharp edge."""
    wedge = math.pi / 2 - rake - clearance
    if not (math.radians(10) <= wedge < math.pi):
        raise ValueError(f"rake {math.degrees(rake):g} deg and clearance {math.degrees(clearance):g} deg "
                         f"leave a wedge of {math.degrees(wedge):g} deg (at least 10 deg)")
    if clearance <= 0 or edge_radius < 0 or rake_length <= edge_radius or flank_length <= edge_radius:
        raise ValueError("the tool needs clearance > 0, edge_radius >= 0 and faces longer than the edge radius")
    t_rake = np.array([math.sin(rake), math.cos(rake)])          # up the rake face
    t_flank = np.array([math.cos(clearance), math.sin(clearance)])  # back along the flank face
    n_rake = np.array([-math.cos(rake), math.sin(rake)])         # outward normals
    n_flank = np.array([math.sin(clearance), -math.cos(clearance)])
    # the ideal sharp edge at the origin; the arc's centre on the wedge bisector, tangent to both faces
    bisector = (t_rake + t_flank) / np.linalg.norm(t_rake + t_flank)
    center = bisector * edge_radius / math.sin(wedge / 2)
    start = math.atan2(n_rake[1], n_rake[0]) % (2 * math.pi)       # 180 deg - rake
    end = start + (math.pi - wedge)                                # through straight down to the flank normal
    if edge_radius > 0:
        n_arc = arc_segments or max(4, math.ceil(math.degrees(end - start) / 5))
        angles = np.linspace(start, end, n_arc + 1)
        bottom = 1.5 * math.pi                                     # the tip is a vertex
        if angles.min() < bottom < angles.max() and np.abs(angles - bottom).min() > 1e-9:
            angles = np.sort(np.append(angles, bottom))
        arc = center + edge_radius * np.column_stack([np.cos(angles), np.sin(angles)])
    else:
        arc = np.zeros((1, 2))
    rake_top = arc[0] + (rake_length - edge_radius) * t_rake
    flank_end = arc[-1] + (flank_length - edge_radius) * t_flank
    back = np.array([max(flank_end[0], rake_top[0]), max(rake_top[1], flank_end[1])])
    pts = [rake_top, *arc, flank_end]
    if np.linalg.norm(back - flank_end) > 1e-12 * rake_length and np.linalg.norm(back - rake_top) > 1e-12 * rake_length:
        pts.append(back)
    vertices = np.array(pts)
    lowest = center[1] - edge_radius if edge_radius > 0 else 0.0
    shift = np.array(tip) - np.array([center[0] if edge_radius > 0 else 0.0, lowest])
    n = len(arc)
    return ToolPolygon(vertices=vertices + shift, rake=rake, clearance=clearance, edge_radius=edge_radius,
                       edge_center=center + shift, rake_segment=(0, 1), flank_segment=(n, n + 1), arc=(1, n))


def from_scene(cutting, tip: tuple[float, float] = (0.0, 0.0)) -> ToolPolygon:
    """The tool of a scene's validated ``[cutting]`` table."""
    h = cutting.uncut_thickness
    return tool_polygon(rake=math.radians(cutting.rake), clearance=math.radians(cutting.clearance),
                        edge_radius=cutting.edge_radius, rake_length=cutting.rake_length or 6 * h,
                        flank_length=cutting.flank_length or 4 * h, tip=tip)
