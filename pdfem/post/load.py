"""Opening a results file for post-processing, with a message naming the file if it is not one.

:func:`load_results` is :func:`pdfem.output.read_results` behind checks that turn a missing,
non-HDF5 or foreign file into an :class:`~pdfem.errors.InputError` (exit status 2).
"""

from __future__ import annotations

import os
from pathlib import Path

import h5py

from pdfem.errors import InputError
from pdfem.output.files import open_for_reading
from pdfem.output.reader import read_results


def load_results(path: str | os.PathLike) -> dict:
    """Read a pdfem results file, refusing anything else with a message that names the file.

    Parameters
    ----------
    path
        The HDF5 results file a run wrote (``results/<case>/results.h5``).

    Returns
    -------
    dict
        :func:`pdfem.output.read_results` of the file, with ``"file"`` (the path as given) added.

    Raises
    ------
    InputError
        If the file does not exist, is not HDF5, or is HDF5 without pdfem's ``/meta`` and
        ``/time``, or cannot be read.
    """
    p = Path(path)
    name = str(path)
    hint = "give the results.h5 that 'pdfem run' wrote (results/<case>/results.h5)"
    if not p.is_file():
        raise InputError(name, None, f"no such results file; {hint}")
    if p.suffix.lower() == ".xdmf":
        raise InputError(name, None, "this is the XDMF view of a results file; give the .h5 "
                         "file beside it")
    try:
        is_hdf5 = h5py.is_hdf5(p)
    except OSError as exc:
        raise InputError(name, None, f"cannot read the file ({exc})") from None
    if not is_hdf5:
        raise InputError(name, None, f"not an HDF5 file, so not a pdfem results file; {hint}")
    try:
        with open_for_reading(p) as f:
            missing = [k for k in ("meta", "time", "ice") if k not in f]
        if missing:
            raise InputError(name, None, "an HDF5 file but not a pdfem results file (no "
                             + ", ".join(f"/{k}" for k in missing) + f"); {hint}")
        results = read_results(p)
    except InputError:
        raise
    except (OSError, KeyError, ValueError, TypeError) as exc:
        raise InputError(name, None, f"cannot be read as a pdfem results file ({exc})") from None
    results["file"] = name
    return results
