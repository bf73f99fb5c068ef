"""The 3D mesh reader (edp/plugins/wendel_mesh.cpp, lib/mesh.idp): the mesh gmshload3 gives, bit for bit (vertices,
tetrahedra, boundary triangles and their orientation, labels, face adjacency, boundary links, vertex normals,
measures), without FreeFEM's face hash table; meshes it does not cover go through FreeFEM's own construction."""

from __future__ import annotations

import subprocess

import pytest

from wendel import freefem

PROBE = """load "msh3"
load "gmsh"
load "wendel_mesh"
string f = "{path}";
cout << "ascii " << wendelMeshAscii2(f) << endl;
mesh3 Ta = wendelLoadMesh3(f);
mesh3 Tb = gmshload3(f);
cout << "diff " << wendelMeshDiff(Ta, Tb) << " nt " << Ta.nt << " nbe " << Ta.nbe << endl;
cout << "volume " << int3d(Ta)(1.) << " " << int3d(Tb)(1.) << endl;
"""


def probe(tmp_path, msh) -> dict:
    script = tmp_path / "probe.edp"
    script.write_text(PROBE.format(path=msh))
    p = subprocess.run(["FreeFem++-mpi", "-nw", "-v", "0", str(script)], env=freefem.environment(),
                       capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stdout + p.stderr
    out = {}
    for line in p.stdout.splitlines():
        words = line.split()
        if words and words[0] in ("ascii", "diff", "volume"):
            out[words[0]] = words[1:]
    return out


def test_the_reader_gives_gmshload3s_mesh(tmp_path):
    from wendel.meshes.builders import box

    msh = tmp_path / "box.msh"
    box(msh, h=0.25, refine={"center": [0.5, 0.5, 1.0], "radius": 0.15, "thickness": 0.3, "ratio": 0.25})
    out = probe(tmp_path, msh)
    assert out["ascii"] == ["1"]
    assert out["diff"][0] == "0" and int(out["diff"][2]) > 500 and int(out["diff"][4]) > 100
    assert float(out["volume"][0]) == pytest.approx(1.0, rel=1e-12)


# two tetrahedra sharing the face (2, 3, 4), node numbers not 1..n (a map), every outer face labelled and the
# shared face too: a boundary triangle between two tetrahedra, which FreeFEM's own construction handles
TWO_TETS = """$MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
5
10 0 0 0
20 1 0 0
30 0 1 0
40 0 0 1
55 1 1 1
$EndNodes
$Elements
{count}
1 15 2 9 1 10
2 4 2 1 1 10 20 30 40
3 4 2 2 2 20 30 40 55
4 2 2 5 1 10 30 20
5 2 2 5 1 10 20 40
6 2 2 5 1 10 40 30
7 2 2 6 1 20 30 55
8 2 2 6 1 20 55 40
9 2 2 6 1 30 40 55
{inner}$EndElements
"""


@pytest.mark.parametrize("inner", ["", "10 2 2 7 1 20 30 40\n"])
def test_small_meshes_and_the_fallback(tmp_path, inner):
    msh = tmp_path / "two.msh"
    msh.write_text(TWO_TETS.format(count=9 + bool(inner), inner=inner))
    out = probe(tmp_path, msh)
    assert out["ascii"] == ["1"]
    assert out["diff"][:5] == ["0", "nt", "2", "nbe", str(6 + bool(inner))]
    assert float(out["volume"][0]) == pytest.approx(float(out["volume"][1]), rel=1e-14)


def test_a_binary_file_goes_to_gmshload3(tmp_path):
    msh = tmp_path / "b.msh"
    msh.write_bytes(b"$MeshFormat\n2.2 1 8\n")
    script = tmp_path / "probe.edp"
    script.write_text(f'load "wendel_mesh"\ncout << "ascii " << wendelMeshAscii2("{msh}") << endl;\n'
                      f'cout << "missing " << wendelMeshAscii2("{tmp_path}/none.msh") << endl;\n')
    p = subprocess.run(["FreeFem++-mpi", "-nw", "-v", "0", str(script)], env=freefem.environment(),
                       capture_output=True, text=True, timeout=60)
    assert "ascii 0" in p.stdout and "missing 0" in p.stdout
