"""How a run stops short: an interruption or a full disk, named with the run folder so that the command
line can say how to resume.
"""

from __future__ import annotations

import contextlib
import errno
import shutil
from pathlib import Path

from .. import freefem
from ..errors import DiskFull, Interrupted


@contextlib.contextmanager
def guarded(root: Path):
    """Name the run folder when a run stops short: Ctrl-C or SIGTERM (FreeFEM is stopped with the driver)
    becomes :class:`Interrupted`, a full disk (of the driver's files or FreeFEM's) :class:`DiskFull`."""
    try:
        yield
    except Interrupted:
        raise
    except KeyboardInterrupt:
        raise Interrupted(root) from None
    except OSError as exc:
        if exc.errno == errno.ENOSPC:
            raise DiskFull(root) from None
        raise
    except (freefem.FreeFemError, ValueError):
        if disk_full(root):
            raise DiskFull(root) from None
        raise


def disk_full(root: Path) -> bool:
    """Whether the file system of ``root`` has (almost) no room left for another increment."""
    try:
        return shutil.disk_usage(root).free < 64 * 1024
    except OSError:
        return False


def stop_leftovers(fem: Path) -> int:
    """Stop FreeFEM processes still writing into ``fem`` (the run folder's fem/): a driver killed in the
    instant between starting a launch and arming its parent-death signal leaves one behind. Only FreeFEM
    launches are matched (a resume must not stop, say, a `tail -f` of the run's log). Returns how many."""
    import os

    marker = f"-out\0{fem}\0".encode()
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            cmdline = Path(f"/proc/{pid}/cmdline").read_bytes()
        except OSError:
            continue
        if b"FreeFem++" in cmdline and marker in cmdline + b"\0":
            found.append(int(pid))
    freefem.terminate(found)
    return len(found)
