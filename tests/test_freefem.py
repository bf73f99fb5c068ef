"""The FreeFEM runner: errors come back as exceptions with the .edp file and line; time limits hold."""

import time

import pytest

from wendel import freefem


def test_compile_error_names_file_and_line(tmp_path):
    lib = tmp_path / "broken.idp"
    lib.write_text("real a = 1;\nreal b = 2;\nreal c = a +* b;\n")
    entry = tmp_path / "entry.edp"
    entry.write_text(f'real z = 0;\ninclude "{lib}"\n')
    with pytest.raises(freefem.FreeFemError) as exc:
        freefem.run(str(entry), [], tmp_path / "out")
    err = exc.value
    assert err.file.endswith("broken.idp") and err.line == 3
    assert "broken.idp:3: syntax error" in str(err)
    assert err.log.is_file()


def test_runtime_error_names_line_and_message(tmp_path):
    entry = tmp_path / "entry.edp"
    entry.write_text("real[int] a(3);\nreal s = 0;\nreal b = a[7];\n")
    with pytest.raises(freefem.FreeFemError) as exc:
        freefem.run(str(entry), [], tmp_path / "out")
    assert exc.value.line == 3
    assert "entry.edp (or a file it includes):3: Out of bound" in str(exc.value)


def test_bad_option_reported_by_the_module(tmp_path):
    import wendel.meshes as meshes

    meshes.build("rectangle", tmp_path / "m.msh", h=0.5)
    (tmp_path / "loads.txt").write_text("1\n1.0\n")
    with pytest.raises(freefem.FreeFemError, match=r"elasticity.idp: -mat_E must be > 0, got -3"):
        freefem.run("mechanics.edp", ["-Ddimension=2", "-mesh", str(tmp_path / "m.msh"), "-loads", str(tmp_path / "loads.txt"),
                                     "-mat_E", "-3"], tmp_path / "out")


def test_time_limit_stops_the_processes(tmp_path):
    entry = tmp_path / "spin.edp"
    entry.write_text("real s = 0;\nfor (int i = 0; i < 2000000000; ++i) s += 1;\n")
    t0 = time.perf_counter()
    with pytest.raises(freefem.FreeFemTimeout, match="time limit of 1 s"):
        freefem.run(str(entry), [], tmp_path / "out", timeout=1.0)
    assert time.perf_counter() - t0 < 10
    import subprocess

    left = subprocess.run(["pgrep", "-f", str(entry)], capture_output=True, text=True).stdout.strip()
    assert left == ""


def test_missing_entry_script(tmp_path):
    with pytest.raises(freefem.FreeFemError, match="no entry script"):
        freefem.run("solve-9d.edp", [], tmp_path)


def test_work_beside_a_launch_runs_while_freefem_runs_and_its_failure_stops_it(tmp_path):
    """``beside`` (the drilling loop starts its next launch there) runs once, after FreeFEM started and before
    it ends; if it raises, the launch is stopped (no process left) and the error comes through."""
    import subprocess

    entry = tmp_path / "slow.edp"
    # a file written at the start, then some work (0.5-1 s): `beside` sees the process alive
    entry.write_text('{ ofstream f("started.txt"); f << 1 << endl; }\n'
                     "real s = 0;\nfor (int i = 0; i < 3000000; ++i) s += 1;\n"
                     '{ ofstream f("ended.txt"); f << s << endl; }\n')
    seen = []

    def beside():
        out = tmp_path / "out"
        seen.append((out / "ended.txt").exists())
        left = subprocess.run(["pgrep", "-f", str(entry)], capture_output=True, text=True).stdout.split()
        seen.append(bool(left))

    freefem.run(str(entry), [], tmp_path / "out", beside=beside)
    assert seen == [False, True]
    assert (tmp_path / "out" / "ended.txt").is_file()

    def fails():
        raise RuntimeError("beside failed")

    with pytest.raises(RuntimeError, match="beside failed"):
        freefem.run(str(entry), [], tmp_path / "out2", beside=fails)
    time.sleep(0.5)
    left = subprocess.run(["pgrep", "-f", str(entry)], capture_output=True, text=True).stdout.strip()
    assert left == ""
    assert not (tmp_path / "out2" / "ended.txt").exists()
