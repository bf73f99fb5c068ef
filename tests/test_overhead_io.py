"""FreeFEM's increment files written by a thread (edp/plugins/wendel_io.cpp, issue 20): the bytes of
BinaryIO's SaveVec, the values as they were when queued, every file written before a marker queued after it
and before the process ends (also by exit(n)), and a file that cannot be written stops the process with
exit code 3 before any later file."""

from __future__ import annotations

import subprocess

from wendel import freefem
from wendel.results import vtu


def _freefem(tmp_path, body: str) -> subprocess.CompletedProcess:
    script = tmp_path / "io.edp"
    script.write_text('load "BinaryIO"\nload "wendel_io"\n' + body)
    env = dict(freefem.environment(), OMPI_MCA_ess_singleton_isolated="1")
    return subprocess.run(["FreeFem++-mpi", "-nw", "-v", "0", str(script)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=60)


def test_queued_files_are_savevec_bytes_written_in_order_before_exit(tmp_path):
    r = _freefem(tmp_path, """
real[int] a(5000);
for (int i = 0; i < 5000; ++i) a[i] = sin(1.37 * i) * (i + 1) * 1e-3;
SaveVec(a, "savevec.bin");
wendelSave(a, "queued.bin");
a = -1;                                  // the queued copy keeps the values of the call
for (int k = 0; k < 200; ++k) wendelSave(a, "f" + k + ".bin");
wendelWrite("done", "ok\\n");
exit(4);                                 // as a failed Newton step: the queue is still written out
""")
    assert r.returncode == 4, r.stdout + r.stderr
    assert (tmp_path / "queued.bin").read_bytes() == (tmp_path / "savevec.bin").read_bytes()
    assert vtu.read_array(tmp_path / "f199.bin").tolist() == [-1.0] * 5000
    assert (tmp_path / "done").read_text() == "ok\n"
    done = (tmp_path / "done").stat().st_mtime_ns
    assert all((tmp_path / f"f{k}.bin").stat().st_mtime_ns <= done for k in range(200))


def test_a_file_that_cannot_be_written_stops_before_any_later_file(tmp_path):
    r = _freefem(tmp_path, """
real[int] a(10); a = 1;
wendelSave(a, "first.bin");
wendelSave(a, "no-such-folder/second.bin");
wendelSave(a, "third.bin");
wendelWrite("done", "ok\\n");
wendelFlush();
cout << "not reached" << endl;
""")
    assert r.returncode == 3, r.stdout + r.stderr
    assert "cannot write" in r.stderr and "no-such-folder/second.bin" in r.stderr
    assert (tmp_path / "first.bin").is_file()
    assert not (tmp_path / "third.bin").exists() and not (tmp_path / "done").exists()
    assert "not reached" not in r.stdout


def test_vtu_written_at_zlib_level_1_reads_back_bit_for_bit(tmp_path):
    """write_vtu compresses meshio's blocks at vtu.ZLIB_LEVEL (issue 20): still a vtkZLibDataCompressor VTU,
    every field read back by meshio bit for bit, its blocks those of zlib at that level (not meshio's 6)."""
    import base64
    import re
    import zlib

    import meshio
    import numpy as np

    rng = np.random.default_rng(5)
    pts = rng.random((400, 3))
    cells = rng.integers(0, 400, (900, 4))
    point_data = {"u": rng.standard_normal((400, 3)), "T": rng.random(400)}
    cell_data = {"vonMises": [rng.random(900)], "strain_xx": [rng.standard_normal(900) * 1e-3]}
    path = tmp_path / "inc.vtu"
    vtu.write_vtu(path, pts, cells, 3, point_data, cell_data)
    text = path.read_text()
    assert 'compressor="vtkZLibDataCompressor"' in text
    m = meshio.read(path)
    assert np.array_equal(m.points, pts) and np.array_equal(m.cells[0].data, cells)
    assert all(np.array_equal(m.point_data[k], v) for k, v in point_data.items())
    assert all(np.array_equal(m.cell_data[k][0], v[0]) for k, v in cell_data.items())
    # the vonMises array: its header (4 UInt32: blocks, block size, last size, compressed size) in base64,
    # then the one block in base64
    block = re.search(r'Name="vonMises"[^>]*>\s*([A-Za-z0-9+/=]+)', text).group(1)
    assert 'header_type="UInt64"' not in text          # meshio's default header, UInt32
    head = np.frombuffer(base64.b64decode(block[:24]), dtype=np.uint32)
    assert head[0] == 1
    body = base64.b64decode(block[24:])
    assert len(body) == head[3]
    assert body == zlib.compress(cell_data["vonMises"][0].tobytes(), vtu.ZLIB_LEVEL) != \
        zlib.compress(cell_data["vonMises"][0].tobytes())


def test_driver_arrays_are_savevec_bytes_that_freefem_reads_back(tmp_path):
    """vtu.write_array (the state the driver writes after a remesh, the predictor's increment) writes SaveVec's
    bytes: read_array gives the values bit for bit, and FreeFEM's readArray (lib/common.idp) reads them."""
    import numpy as np

    v = np.array([0.1, -1e-300, 1.0 / 3.0, 6.02214076e23, -0.0, 5e-324, np.pi])
    vtu.write_array(tmp_path / "a.txt", v)
    raw = (tmp_path / "a.txt").read_bytes()
    assert raw == (7).to_bytes(8, "little") + v.astype("<f8").tobytes()
    assert np.array_equal(vtu.read_array(tmp_path / "a.txt"), v)
    script = tmp_path / "read.edp"
    script.write_text('include "lib/common.idp"\nreal[int] a(7);\nreadArray("a.txt", a)\ncout.precision(17);\n'
                      'for (int i = 0; i < 7; ++i) cout << "value " << a[i] << endl;\n')
    env = dict(freefem.environment(), OMPI_MCA_ess_singleton_isolated="1")
    r = subprocess.run(["FreeFem++-mpi", "-nw", "-v", "0", str(script), "-out", str(tmp_path)], cwd=tmp_path, env=env,
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stdout + r.stderr
    got = [float(line.split()[1]) for line in r.stdout.splitlines() if line.startswith("value ")]
    assert got == v.tolist()
