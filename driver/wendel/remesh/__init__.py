"""Remeshing a deformed body: element quality (:mod:`.quality`), gmsh meshing of the deformed boundary
(:mod:`.mesher`), transfer of fields (:mod:`.transfer`) and the loop's remesh step (:mod:`.step`)."""
