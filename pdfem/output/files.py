"""Opening results files with HDF5's file lock in mind.

A writer holds HDF5's lock on its file for the whole run. Readers open a locked file without
locking (they see the committed prefix, see :mod:`pdfem.output.writer`); a second writer is
refused before HDF5 would truncate the file. :func:`inside` keeps every file a run writes
inside its output directory.
"""

from __future__ import annotations

import os
from pathlib import Path

import h5py

from pdfem.errors import InputError


def open_for_reading(path: str | os.PathLike) -> h5py.File:
    """Open an HDF5 file read-only, without the file lock if a running writer holds it.

    Raises
    ------
    OSError
        If the file cannot be opened as HDF5.
    """
    try:
        return h5py.File(path, "r")
    except BlockingIOError:  # being written by a run: read without the file lock
        return h5py.File(path, "r", locking=False)


def refuse_if_being_written(path: Path) -> None:
    """Raise if another process holds ``path`` open for writing (its HDF5 file lock).

    HDF5 truncates a file before it finds the lock, so a second run would wipe a running
    run's results: look first, with a read-only open that the writer's lock refuses.

    Raises
    ------
    FileExistsError
        If the file is locked by a writer.
    """
    if not path.exists():
        return
    try:
        h5py.File(path, "r").close()
    except BlockingIOError as err:
        raise FileExistsError(f"results file {str(path)!r} is being written by another "
                              "process; choose another output path") from err
    except OSError:
        return  # not a readable HDF5 file: it is overwritten


METADATA_CACHE_BYTES = 256 * 1024
"""Fixed size of HDF5's metadata cache for a results file being written (see
:func:`bound_metadata_cache`)."""


def bound_metadata_cache(file: h5py.File) -> None:
    """Hold HDF5's metadata cache of ``file`` at ``METADATA_CACHE_BYTES`` (no adaptive growth).

    Every XDMF view is an HDF5 object; with the default adaptive cache (up to 32 MiB) their
    object headers stay cached, and each flush, which walks the cache, took time in proportion
    to the number of frames written (10x after 6,000 frames, ``benchmarks/output_frames.py``).
    A small fixed cache evicts them, and a flush costs the same at every frame.
    """
    c = file.id.get_mdc_config()
    c.set_initial_size = True
    c.initial_size = c.max_size = METADATA_CACHE_BYTES
    c.min_size = METADATA_CACHE_BYTES // 2
    c.incr_mode = c.decr_mode = c.flash_incr_mode = 0  # off
    file.id.set_mdc_config(c)


def inside(directory: str | os.PathLike, name: str) -> Path:
    """The path of the file ``name`` in the output ``directory``, checked to stay inside it.

    Names in a case are validated when it is loaded (:mod:`pdfem.case`); this is the writers'
    own guard that nothing a run writes lands outside its ``--out``.

    Raises
    ------
    InputError
        If ``name`` is empty, absolute, or leads out of ``directory`` (``..``, a separator).
    """
    base = Path(directory).resolve()
    path = (base / name).resolve()
    if not name or Path(name).is_absolute() or path.parent != base:
        raise InputError(None, "--out", f"the output file name {name!r} would not be written "
                         f"directly into the output directory {base}; names of bodies, "
                         "structures, contacts and monitors may hold letters, digits, '_', '-' "
                         "and '.' (not first)")
    return path
