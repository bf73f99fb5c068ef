"""wendel.results.meshfile.read_msh22: gmsh's ASCII MSH 2.2 parsed with numpy gives meshio's Mesh (points,
cell blocks in file order, physical and elementary tags, physical names, dtypes); other files go to meshio."""

from __future__ import annotations

import meshio
import numpy as np
import pytest

from wendel.results.meshfile import read, read_msh22


def _same(a: meshio.Mesh, b: meshio.Mesh) -> None:
    assert a.points.dtype == b.points.dtype and np.array_equal(a.points, b.points)
    assert [c.type for c in a.cells] == [c.type for c in b.cells]
    for x, y in zip(a.cells, b.cells):
        assert x.data.dtype == y.data.dtype and np.array_equal(x.data, y.data)
    assert a.cell_data.keys() == b.cell_data.keys()
    for k in a.cell_data:
        for x, y in zip(a.cell_data[k], b.cell_data[k], strict=True):
            assert x.dtype == y.dtype and np.array_equal(x, y), k
    assert a.field_data.keys() == b.field_data.keys()
    for k in a.field_data:
        assert a.field_data[k].dtype == b.field_data[k].dtype and np.array_equal(a.field_data[k], b.field_data[k])


def _gmsh(path, dim: int) -> None:
    import gmsh

    gmsh.initialize()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        if dim == 3:
            gmsh.model.occ.addBox(0, 0, 0, 1, 2, 0.5)
        else:
            gmsh.model.occ.addRectangle(0, 0, 0, 1, 2)
        gmsh.model.occ.synchronize()
        for d, tag in gmsh.model.getEntities(dim - 1):
            gmsh.model.addPhysicalGroup(d, [tag], name=f"side {tag}")      # a name with a space
        gmsh.model.addPhysicalGroup(dim, [t for _, t in gmsh.model.getEntities(dim)], tag=100, name="domain")
        gmsh.model.addPhysicalGroup(dim - 2, [t for _, t in gmsh.model.getEntities(dim - 2)][:2], name="edges")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.3)
        gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
        gmsh.model.mesh.generate(dim)
        gmsh.write(str(path))
    finally:
        gmsh.finalize()


@pytest.mark.parametrize("dim", [2, 3])
def test_gmsh_meshes_read_as_meshio_reads_them(tmp_path, dim):
    path = tmp_path / f"m{dim}.msh"
    _gmsh(path, dim)
    fast = read_msh22(path)
    assert fast is not None and len(fast.cells) >= 2          # elements of 2 or 3 types, one block each
    _same(fast, meshio.read(path, file_format="gmsh"))
    assert read(path, "gmsh") is not None


HEAD = '$MeshFormat\n2.2 0 8\n$EndMeshFormat\n'
NODES = '$Nodes\n4\n7 0 0 0\n2 1 0 0\n5 0 1 0\n9 0 0 1\n$EndNodes\n'


def test_node_tags_out_of_order_and_element_types_interleaved(tmp_path):
    """Nodes tagged 7, 2, 5, 9 and triangle, tetrahedron, triangle runs: meshio's remap and blocks."""
    path = tmp_path / "m.msh"
    path.write_text(HEAD + '$PhysicalNames\n2\n2 1 "a"\n3 2 "b"\n$EndPhysicalNames\n' + NODES
                    + "$Elements\n4\n1 2 2 1 10 7 2 5\n2 2 2 1 10 7 2 9\n3 4 2 2 20 7 2 5 9\n4 2 2 3 11 2 5 9\n"
                    "$EndElements\n")
    fast = read_msh22(path)
    assert fast is not None and [c.type for c in fast.cells] == ["triangle", "tetra", "triangle"]
    _same(fast, meshio.read(path, file_format="gmsh"))


@pytest.mark.parametrize("elements", [
    "$Elements\n1\n1 4 3 2 20 0 7 2 5 9\n$EndElements\n",      # a partition tag: meshio's warning and rules
    "$Elements\n2\n1 4 2 2 20 7 2 5 9\n$EndElements\n",        # fewer elements than announced
    "$Elements\n1\n1 4 2 2 20 7 2 5\n$EndElements\n",          # a truncated row
    "$Elements\n1\n1 4 2 2 20 7 2 5 8\n$EndElements\n",        # a node that is not in $Nodes
])
def test_files_outside_the_fast_path_go_to_meshio(tmp_path, elements):
    path = tmp_path / "m.msh"
    path.write_text(HEAD + NODES + elements)
    assert read_msh22(path) is None
    binary = tmp_path / "b.msh"
    binary.write_text("$MeshFormat\n2.2 1 8\n$EndMeshFormat\n" + NODES)
    assert read_msh22(binary) is None
