"""wendel: thermo-elastoplastic contact simulations with FreeFEM and gmsh, driven from Python.

Public API: :func:`wendel.scene.load` (read and validate a scene file), :func:`wendel.loop.run`
(run a scene), :func:`wendel.results.study.study` (error against run time over refined meshes).
"""

__version__ = "0.1.0"
