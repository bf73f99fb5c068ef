"""Run FreeFEM entry scripts: environment, MPI launch, time limit, log, errors turned into exceptions.

Every launch is ``mpirun -np N FreeFem++-mpi -nw -v 0 edp/<entry>.edp -out DIR -DNAME=VALUE ... -key value ...``,
on one rank ``FreeFem++-mpi ...`` alone (an MPI singleton: the same program, 0.3 s less start-up here). ``-D`` arguments define FreeFEM macros
before the script compiles (they choose the modules, :func:`wendel.loop.launch.macros`); the others are
read by ``getARGV`` at run time. FreeFEM's output goes to a log file; results come
back as files (the exit code says which file to read), never scraped from stdout except to quote a
compile or runtime error.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import select
import signal
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
EDP = ROOT / "edp"
PLUGINS = ROOT / "build" / "plugins"

EXIT_BAD_OPTION = 3   # edp wrote error.txt (wendelFail)
EXIT_NEWTON = 4       # edp wrote failed.json (an increment did not converge)


class FreeFemError(RuntimeError):
    """FreeFEM stopped: a compile or runtime error (with file and line), a bad option, or a crash."""

    def __init__(self, message: str, file: str | None = None, line: int | None = None, log: Path | None = None):
        super().__init__(message)
        self.file, self.line, self.log = file, line, log


class FreeFemTimeout(FreeFemError):
    """A launch ran past its time limit and was stopped."""


def read_json(text: str) -> dict:
    """JSON that FreeFEM wrote, whose numbers may be C's ``nan``, ``-nan``, ``inf`` (a diverged Newton step).

    >>> read_json('{"residual": -nan, "r": inf, "s": -inf}')
    {'residual': nan, 'r': inf, 's': -inf}
    """
    text = re.sub(r"(:\s*)-?nan\b", r"\1NaN", text)
    return json.loads(re.sub(r"(:\s*)(-?)inf\b", r"\1\2Infinity", text))


class NewtonFailure(RuntimeError):
    """An increment did not converge; ``record`` is edp's failed.json (increment, load factor, reason)."""

    def __init__(self, record: dict):
        super().__init__(f"Newton failed at increment {record.get('increment')} "
                         f"(load factor {record.get('load_factor')}): {record.get('reason', 'no convergence')}")
        self.record = record


@dataclass
class Launch:
    """What one launch took: wall time and the command."""

    wall: float
    command: list[str]


def environment() -> dict[str, str]:
    """The environment FreeFEM needs here (include and plugin paths, MPI as root, single-threaded BLAS)."""
    env = dict(os.environ)
    env.update({
        "FF_INCLUDEPATH": f"/usr/include/freefem++/idp;{EDP}",
        "FF_LOADPATH": f"{PLUGINS};/usr/lib/freefem++/mpi",
        "OMPI_ALLOW_RUN_AS_ROOT": "1",
        "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
        "OMPI_MCA_pml": "ob1",
        "OMPI_MCA_btl": "self,vader",
        "OMPI_MCA_rmaps_base_oversubscribe": "1",
        "OPENBLAS_NUM_THREADS": "1",
        "OMP_NUM_THREADS": "1",
    })
    return env


_COMPILE = re.compile(r"Error line number (\d+), in file (.*?), before\s+token (.*)")
_CURRENT = re.compile(r"current line = (\d+)")
_EXEC = re.compile(r"(Exec error : .*|Compile error : .*|Load error : .*|.*Error.*)")


def _project_file(name: str, script: Path) -> str | None:
    """``name`` if it is an existing .edp/.idp file of the project (edp/) or beside the entry script run,
    else None: a path printed in the log by anything else (a run folder named like an error message) is
    not a location."""
    path = Path(name)
    for root in (EDP, script.parent):
        full = path if path.is_absolute() else root / path
        try:
            full = full.resolve()
        except OSError:
            continue
        if full.suffix in (".edp", ".idp") and full.is_relative_to(root.resolve()) and full.is_file():
            return name
    return None


def explain_log(text: str, script: Path) -> tuple[str, str | None, int | None]:
    """Turn FreeFEM's log into (message, file, line); only the project's own .edp/.idp files are locations.

    >>> explain_log(" Error line number 2, in file lib/bc.idp, before  token *\\nsyntax error\\n", Path("x.edp"))
    ('lib/bc.idp:2: syntax error (before token *)', 'lib/bc.idp', 2)
    >>> explain_log(" Error line number 1, in file /etc/shadow, before  token *\\n", Path("x.edp"))[1:]
    (None, None)
    """
    for m in _COMPILE.finditer(text):
        line, file, token = int(m.group(1)), m.group(2).strip(), m.group(3).strip()
        file = file.split(" in ")[-1] if file.startswith("macro:") else file
        if _project_file(file, script) is None:
            continue
        after = text[m.end():].strip().splitlines()
        what = after[0].strip() if after else "compile error"
        return f"{file}:{line}: {what} (before token {token})", file, line
    m = _CURRENT.search(text)
    if m:
        line = int(m.group(1))
        ex = re.search(r"Exec error : (.*)", text) or re.search(r"(Load error : .*)", text)
        what = ex.group(1).strip() if ex else text.strip().splitlines()[-1]
        return f"{script.name} (or a file it includes):{line}: {what}", str(script), line
    tail = "\n".join(text.strip().splitlines()[-5:])
    return f"FreeFEM stopped without a located error; log tail:\n{tail}", None, None


def _command(entry: str, options: list[str], out_dir: Path, ranks: int, gate: bool = False):
    """The script, command line and environment of a launch."""
    script = Path(entry) if Path(entry).is_absolute() else EDP / entry
    if not script.is_file():
        raise FreeFemError(f"no entry script {script}")
    out_dir.mkdir(parents=True, exist_ok=True)
    # setpriv: mpirun gets SIGTERM (and stops its ranks) when the driver dies, even by kill -9
    # one rank: FreeFem++-mpi started alone (an MPI singleton), 0.2 s here against 0.5 s through mpirun
    # (not inside a SLURM job: there Open MPI's singleton looks for SLURM's PMI, which Debian's lacks, and aborts)
    singleton = ranks == 1 and not any(k.startswith("SLURM_JOB") for k in os.environ)
    mpi = [] if singleton else ["mpirun", "-np", str(ranks)]
    cmd = ["setpriv", "--pdeathsig", "TERM", *mpi, "FreeFem++-mpi", "-nw", "-v", "0",
           str(script), *(["-DWITHGATE=1"] if gate else []), "-out", str(out_dir), *options]
    env = environment()
    # Open MPI's session folder of this launch alone: concurrent runs (a sweep) sharing one raced
    # ("orte_session_dir failed") when the first to finish removed it
    session = tempfile.mkdtemp(prefix="wendel-ompi-")
    env.setdefault("OMPI_MCA_orte_tmpdir_base", session)
    if singleton:       # no orted beside the singleton: 0.1 s less per launch here (issue 20)
        env.setdefault("OMPI_MCA_ess_singleton_isolated", "1")
    return script, cmd, env, session, singleton


def _popen(cmd, env, out_dir: Path, log: Path, stdin) -> subprocess.Popen:
    with open(log, "a") as flog:
        flog.write("$ " + " ".join(cmd) + "\n")
        flog.flush()
        return subprocess.Popen(cmd, stdin=stdin, stdout=flog, stderr=subprocess.STDOUT, env=env,
                                start_new_session=True, cwd=out_dir)


def run(entry: str, options: list[str], out_dir: Path, ranks: int = 1, timeout: float = 3600.0,
        log: Path | None = None, started=None, beside=None) -> Launch:
    """Run ``edp/<entry>`` with ``options`` on ``ranks`` MPI ranks; output files go to ``out_dir``.
    ``started``: a launch :func:`wendel.prestart.start` made ahead; taken when its entry, options, folder,
    log and rank count are these and it still waits (else stopped, and this launch started as usual).
    ``beside``: called once FreeFEM runs (after its "go" or its start), before the wait: work that must not
    delay the launch (the drilling loop starts the next launch there: spawning a process took 12 ms of the
    driver's time per launch on the loaded 2 cores, 0.6 s of drilling-deep-rz, issue 20).

    Raises :class:`FreeFemError` (with .file and .line), :class:`FreeFemTimeout` or
    :class:`NewtonFailure`.
    """
    log = log or out_dir / "freefem.log"
    for stale in ("error.txt", "failed.json"):
        (out_dir / stale).unlink(missing_ok=True)
    if started is not None and not ((started.entry, started.options, started.out_dir, started.log, ranks)
                                    == (entry, list(options), out_dir, log, 1) and started.proc.poll() is None):
        _kill(started.proc)         # not this launch: stopped unused (wendel.prestart.abandon)
        started.proc.stdin.close()
        shutil.rmtree(started.session, ignore_errors=True)
        started = None
    t0 = time.perf_counter()
    if started is not None:
        script = Path(entry) if Path(entry).is_absolute() else EDP / entry
        proc, cmd, session = started.proc, started.cmd, started.session
        if started.nice is not None:        # started early at nice 19 (wendel.prestart): the driver's priority
            _renice(proc.pid, started.nice)
        try:
            proc.stdin.write(b"go\n")
            proc.stdin.close()
        except OSError:          # it ended (seen as its exit code below)
            pass
    else:
        script, cmd, env, session, _ = _command(entry, options, out_dir, ranks)
        proc = _popen(cmd, env, out_dir, log, subprocess.DEVNULL)
    try:
        if beside is not None:
            beside()
        rc = _wait(proc, timeout)
    except subprocess.TimeoutExpired:
        _kill(proc)
        raise FreeFemTimeout(f"{entry}: stopped after the time limit of {timeout:g} s (numerics.timeout)",
                             str(script), None, log) from None
    except BaseException:
        _kill(proc)
        raise
    finally:
        shutil.rmtree(session, ignore_errors=True)
    wall = time.perf_counter() - t0
    if rc == 0:
        return Launch(wall, cmd)
    if rc == EXIT_NEWTON and (out_dir / "failed.json").is_file():
        raise NewtonFailure(read_json((out_dir / "failed.json").read_text()))
    if (out_dir / "error.txt").is_file():
        raise FreeFemError((out_dir / "error.txt").read_text().strip(), str(script), None, log)
    text = log.read_text(errors="replace")
    text = text[text.rfind("$ " + " ".join(cmd)):]       # this launch's part of the log
    message, file, line = explain_log(text, script)
    raise FreeFemError(f"FreeFEM error (exit code {rc}) in {message}\n(full log: {log})", file, line, log)


def terminate(pids: list[int], grace: float = 3.0) -> None:
    """SIGTERM the processes ``pids``, then SIGKILL those still there after ``grace`` seconds (processes
    of a run found by their command line: a launch that outlived its driver, an earlier sweep attempt)."""
    for sig in (signal.SIGTERM, signal.SIGKILL):
        left = [p for p in pids if alive(p)]
        for p in left:
            try:
                os.kill(p, sig)
            except ProcessLookupError:
                pass
        deadline = time.monotonic() + grace
        while time.monotonic() < deadline and any(alive(p) for p in left):
            time.sleep(0.05)


def alive(pid: int) -> bool:
    """Whether the process ``pid`` exists (a zombie counts until it is reaped)."""
    try:
        os.kill(pid, 0)
        return True
    except ProcessLookupError:
        return False


def _wait(proc: subprocess.Popen, timeout: float) -> int:
    """``proc.wait(timeout)`` woken by the process's end itself (a pidfd) rather than by Popen's polling,
    whose sleeps grow to 0.05 s: up to 0.05 s less per launch (issue 20)."""
    try:
        fd = os.pidfd_open(proc.pid)
    except (AttributeError, OSError):        # not Linux >= 5.3
        return proc.wait(timeout=timeout)
    try:
        poller = select.poll()
        poller.register(fd, select.POLLIN)
        if not poller.poll(max(timeout, 0.0) * 1000.0):
            raise subprocess.TimeoutExpired(proc.args, timeout)
    finally:
        os.close(fd)
    return proc.wait()


def _renice(pid: int, nice: int) -> None:
    """Give every thread of the process ``pid`` the priority ``nice`` (Linux: a priority is per thread, and
    threads made before carry the old one)."""
    try:
        tids = [int(t) for t in os.listdir(f"/proc/{pid}/task")]
    except OSError:
        tids = [pid]
    for tid in tids:
        try:
            os.setpriority(os.PRIO_PROCESS, tid, nice)
        except (ProcessLookupError, PermissionError):
            pass


def _kill(proc: subprocess.Popen) -> None:
    """Stop mpirun and its ranks (the whole process group)."""
    for sig in (signal.SIGTERM, signal.SIGKILL):
        try:
            os.killpg(proc.pid, sig)
        except ProcessLookupError:
            return
        try:
            proc.wait(timeout=3)
            return
        except subprocess.TimeoutExpired:
            continue
