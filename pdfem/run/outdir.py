"""The output directory of a run (``--out``): checked before anything is built, and held by
one run at a time.

:func:`check_out_dir` refuses an ``--out`` that is a file, cannot be created or is not
writable (exit 2, no traceback). :class:`OutDirLock` is an exclusive lock file
``<out>/pdfem.lock`` (created with ``O_CREAT | O_EXCL``, holding the pid and host of its run):
a second run into the same directory is refused naming the holder's pid; a lock left by a dead
process (a killed run) is taken over; the lock is removed when the run ends, also on errors.
Under MPI only rank 0 takes it.
"""

from __future__ import annotations

import os
import socket
from pathlib import Path

from pdfem.errors import InputError

LOCK_NAME = "pdfem.lock"
"""Name of the lock file in the output directory."""


def check_out_dir(out: str | os.PathLike) -> Path:
    """Create the output directory if needed and check that the run can write into it.

    Raises
    ------
    InputError
        (field ``--out``) If the path is a file, cannot be created, or is not writable.
    """
    p = Path(out)
    if p.exists() and not p.is_dir():
        raise InputError(None, "--out", f"{p} is a file, not a directory; give a directory for "
                         "the results (it is created if missing)", str(out))
    try:
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(None, "--out", f"cannot create the output directory {p}: "
                         f"{exc.strerror or exc}; give a directory you can write to",
                         str(out)) from None
    probe = p / f".pdfem-write-test-{os.getpid()}"
    try:
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise InputError(None, "--out", f"the output directory {p} is not writable: "
                         f"{exc.strerror or exc}; give a directory you can write to",
                         str(out)) from None
    return p


def _alive(pid: int) -> bool:
    """Whether a process ``pid`` exists on this host."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:  # a killed run not yet reaped by its parent is a zombie: dead for our purpose
        stat = Path(f"/proc/{pid}/stat").read_text()
        return stat.rpartition(")")[2].split()[0] != "Z"
    except (OSError, IndexError):
        return True


def _holder(path: Path) -> tuple[int, str]:
    """The pid and host written in a lock file (0 and "" when unreadable)."""
    try:
        pid, _, host = path.read_text().strip().partition("@")
        return int(pid), host
    except (OSError, ValueError):
        return 0, ""


class OutDirLock:
    """Exclusive lock of an output directory for the duration of a ``with`` block.

    Parameters
    ----------
    out
        The output directory (exists: :func:`check_out_dir`).
    enabled
        False on MPI ranks other than 0 (they neither take nor release it).
    """

    def __init__(self, out: str | os.PathLike, enabled: bool = True) -> None:
        self.path = Path(out) / LOCK_NAME
        self.enabled = enabled
        self.held = False

    def acquire(self) -> None:
        """Take the lock, taking over one left by a dead process.

        Raises
        ------
        InputError
            (field ``--out``) If a living process holds it.
        """
        host = socket.gethostname()
        for _ in range(3):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                pid, where = _holder(self.path)
                if (where in ("", host) and not _alive(pid)) or pid == 0:
                    self.path.unlink(missing_ok=True)  # stale: its run was killed
                    continue
                raise InputError(None, "--out", f"another pdfem run (pid {pid}"
                                 f"{' on ' + where if where and where != host else ''}) is "
                                 f"writing into {self.path.parent} (lock file {self.path}); "
                                 "wait for it to finish or choose another output directory",
                                 str(self.path.parent)) from None
            with os.fdopen(fd, "w") as fh:
                fh.write(f"{os.getpid()}@{host}\n")
            self.held = True
            return
        raise InputError(None, "--out", f"cannot take the lock file {self.path}; remove it if "
                         "no run is writing there", str(self.path.parent))

    def release(self) -> None:
        """Remove the lock file if this process holds it."""
        if self.held and _holder(self.path)[0] == os.getpid():
            self.path.unlink(missing_ok=True)
        self.held = False

    def __enter__(self) -> "OutDirLock":
        if self.enabled:
            self.acquire()
        return self

    def __exit__(self, *exc) -> None:
        self.release()
