"""Room on disk for the HDF5 files a run writes, and what a write that finds none does.

HDF5 does not survive a failed write. Measured with h5py 3.16 / HDF5 2.0 under a file-size
limit (``ulimit -f``; Python ignores SIGXFSZ, so ``write`` fails with EFBIG): the flush that
fails has already written the superblock with the file's new end, so the file no longer opens
("truncated file: eof < stored_eof") and every frame in it is lost; closing the file then
raises again, and h5py's clean-up of it ends the process with a segmentation fault. Hence:

- :class:`Room` reserves disk space ahead of a results file's end (``posix_fallocate``, which
  fails with EFBIG, ENOSPC or EDQUOT before anything is written) before every write that can
  grow the file, with a margin that grows if a write ever needed more. A write that finds no
  room is refused before HDF5 touches the file, which stays as its last flush left it: whole
  and readable. :meth:`Room.trim` gives the unused reserve back when the file is closed.
- :func:`release` closes an HDF5 file after a failed write without writing to it again: its
  descriptor is pointed at ``/dev/null`` first, so HDF5's closing flush succeeds and changes
  nothing on disk, and no error is raised on the way out.
- :func:`write_atomically` writes a whole file (a checkpoint) beside its place and moves it
  there only when it is complete and on disk; a failure leaves the previous file untouched.
- :func:`failure` says in one paragraph what failed, where and why (no space, a file-size limit,
  a quota, an I/O error) for :class:`pdfem.errors.OutputError`.
"""

from __future__ import annotations

import errno
import os
import re
import resource
from collections.abc import Callable
from pathlib import Path

import h5py

from pdfem.errors import OutputError

MARGIN = 256 * 1024
"""Bytes reserved beyond what a write's own data needs (HDF5's metadata: object headers, chunk
indexes, heaps); doubled whenever a write needed more."""

CAUSES = {errno.ENOSPC: "no space is left on the device",
          errno.EFBIG: "the file would pass the file-size limit",
          errno.EDQUOT: "the disk quota is used up",
          errno.EIO: "the device reported an input/output error"}
"""The write errors a run reports as such (anything else is also reported, by its name)."""

_UNSUPPORTED = (errno.EOPNOTSUPP, errno.EINVAL, errno.ENOSYS, errno.ENODEV)
"""``posix_fallocate`` errors that mean "not on this file system": no reservation then."""


class NoRoom(OSError):
    """The room a write needs could not be reserved (``errno``: ENOSPC, EFBIG, EDQUOT, ...);
    HDF5 did not write for it."""


class Room:
    """Disk space reserved ahead of the end of an HDF5 file being written.

    Parameters
    ----------
    path
        The file (its size is trimmed back on :meth:`trim`).
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self.margin = MARGIN
        self.end = 0          # where the last reserve ends, bytes
        self.enabled = hasattr(os, "posix_fallocate")

    def ensure(self, file: h5py.File, nbytes: int) -> None:
        """Before a write: have ``nbytes`` + the margin allocated on disk beyond the end HDF5
        knows of ``file`` (a no-op for the file system where they already are).

        Raises
        ------
        NoRoom
            ENOSPC, EFBIG, EDQUOT, EIO, ...: the room is not there.
        """
        start = file.id.get_filesize()
        self._allocate(file, start, start + int(nbytes) + self.margin)

    def keep(self, file: h5py.File) -> None:
        """During a write: have the reserve of :meth:`ensure` still allocated (HDF5 cuts the
        file back to its end on some flushes).

        Raises
        ------
        NoRoom
            As :meth:`ensure`.
        """
        self._allocate(file, file.id.get_filesize(), self.end)

    def _allocate(self, file: h5py.File, start: int, end: int) -> None:
        if not self.enabled:
            return
        self.end = end
        if end <= start:
            return
        try:
            os.posix_fallocate(file.id.get_vfd_handle(), start, end - start)
        except OSError as exc:
            if exc.errno not in _UNSUPPORTED:
                raise NoRoom(exc.errno, exc.strerror) from None
            self.enabled = False  # a file system without it: HDF5 writes unprotected

    def observe(self, file: h5py.File) -> None:
        """After a write: if HDF5 went past the reserve, reserve more from now on."""
        if self.enabled and file.id.get_filesize() > self.end:
            self.margin *= 2

    def trim(self, size: int) -> None:
        """Give back the reserve beyond ``size`` bytes (the closed file's end or more)."""
        try:
            if self.path.stat().st_size > size:
                os.truncate(self.path, size)
        except OSError:
            pass  # the reserve stays: the file is larger than it needs, and reads the same


def release(file: h5py.File) -> None:
    """Close an HDF5 file after a failed write without writing to it again: its descriptor is
    pointed at ``/dev/null`` first, so the file on disk stays as it was (see the module
    docstring); errors on the way out are dropped."""
    if not file:
        return
    try:
        null = os.open(os.devnull, os.O_RDWR)
        try:
            os.dup2(null, file.id.get_vfd_handle())
        finally:
            os.close(null)
        file.close()
    except (OSError, RuntimeError, ValueError):
        pass


def error_number(exc: BaseException) -> int | None:
    """The ``errno`` of a failed write: an ``OSError``'s own, or the one HDF5 puts in its
    message (``errno = 28``)."""
    if isinstance(exc, OSError) and exc.errno:
        return exc.errno
    m = re.search(r"errno = (\d+)", str(exc))
    return int(m[1]) if m else None


def cause(exc: BaseException, path: Path) -> str:
    """Why a write to ``path`` failed, in words, with the limit or the space left and the
    error's name: "no space is left on the device (1,024 bytes free in /scratch; ENOSPC)"."""
    code = error_number(exc)
    text = CAUSES.get(code, os.strerror(code) if code else str(exc).split("(")[0].strip())
    notes = []
    if code == errno.EFBIG:
        limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
        if limit != resource.RLIM_INFINITY:
            notes.append(f"{limit:,} bytes, ulimit -f")
    elif code == errno.ENOSPC:
        try:
            st = os.statvfs(path.parent)
            notes.append(f"{st.f_bavail * st.f_frsize:,} bytes free in {path.parent}")
        except OSError:
            pass
    if code in errno.errorcode:
        notes.append(errno.errorcode[code])
    return f"{text} ({'; '.join(notes)})" if notes else text


def failure(what: str, path: Path, exc: BaseException, kept: str) -> str:
    """The one-paragraph message of a failed write: ``what`` failed writing ``path`` because
    of ``exc``; ``kept`` says what stays readable and what to do."""
    return f"writing {what} to {path} failed: {cause(exc, path)}. {kept}"


def write_atomically(path: Path, fill: Callable[[h5py.File], None], what: str) -> int:
    """Write the HDF5 file ``path`` whole or not at all, and return its size in bytes.

    ``fill`` writes the content into ``path.tmp``, which is closed, fsync'ed and moved over
    ``path`` with ``os.replace``. A write error (no space, a file-size limit, an I/O error) at
    any point removes the temporary file and leaves ``path`` as it was.

    Raises
    ------
    OutputError
        The write failed; the message names ``what``, the cause and the bytes written.
    """
    tmp = path.with_name(path.name + ".tmp")
    f = None
    try:
        f = h5py.File(tmp, "w")
        fill(f)
        f.close()
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except (OSError, RuntimeError) as exc:
        written = tmp.stat().st_size if tmp.exists() else 0
        if f is not None:
            release(f)
        tmp.unlink(missing_ok=True)
        raise OutputError(failure(what, tmp, exc, f"{written:,} bytes of it were written "
                                  "and removed again.")) from None
    except BaseException:
        if f is not None:
            release(f)
        tmp.unlink(missing_ok=True)
        raise
    return path.stat().st_size
