"""Boundary and domain labels shared by the gmsh builders and the .idp files.

A label number is the gmsh physical tag of a named boundary and the FreeFEM label of the same
boundary. Scenes name boundaries; the driver turns names into these numbers.

>>> LABELS["top"]
4
"""

LABELS = {
    "left": 1,      # x = x0
    "right": 2,     # x = x1
    "bottom": 3,    # y = y0 in 2D, z = z0 in 3D
    "top": 4,       # y = y1 in 2D, z = z1 in 3D
    "front": 5,     # y = y0 in 3D
    "back": 6,      # y = y1 in 3D
    "inner": 7,     # inner surface of a hollow body
    "outer": 8,     # outer surface of a hollow body
    "axis": 9,      # the axis r = 0 of an axisymmetric (r, z) section (u_r = 0 there, set by FreeFEM)
    "symmetry_x": 11,  # plane x = 0 of a symmetric model
    "symmetry_y": 12,  # plane y = 0 of a symmetric model
    "free_surface": 21,  # orthogonal cutting: the uncut surface that becomes the chip's back
    "machined": 22,      # orthogonal cutting: the machined surface behind the tool
    "bore_wall": 23,   # cylindrical wall of a drilled bore (meshes/drilling.py)
    "bore_bottom": 24,  # tip cone at the bottom of a drilled bore
    "layer_end": 25,   # orthogonal cutting: the far end of the cut layer (left of the uncut layer, free)
    "opened": 31,      # DG separation: both sides of the faces a separating run opened (separated.msh)
    "domain": 100,  # the body itself
}

NAMES = {number: name for name, number in LABELS.items()}
