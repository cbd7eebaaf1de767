"""Comparing and watching results files from a test.

:func:`assert_same_results` compares two runs' results files array by array, bit for bit (the
reference of every restart test: the uninterrupted run); :func:`committed_frames` counts the
frames a running run has committed, for tests that act on a run mid-way.
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from pdfem.output import read_results

UNCOMPARED = ("meta/created",)
"""Entries that differ between two runs of the same case by design (the time of the run)."""


def _flat(tree: dict, prefix: str = "") -> dict:
    out = {}
    for k, v in tree.items():
        if isinstance(v, dict):
            out.update(_flat(v, f"{prefix}{k}/"))
        else:
            out[prefix + k] = v
    return out


def assert_same_results(a: Path, b: Path) -> None:
    """Every frame, history and attribute of the results files ``a`` and ``b``
    (:func:`pdfem.output.read_results`) equal bit for bit, but :data:`UNCOMPARED`."""
    ra, rb = _flat(read_results(a)), _flat(read_results(b))
    assert sorted(ra) == sorted(rb), set(ra) ^ set(rb)
    for k in ra:
        if k not in UNCOMPARED:
            np.testing.assert_array_equal(ra[k], rb[k], err_msg=k)


def committed_frames(path: Path) -> int:
    """Frames committed to the results file ``path`` of a running run (0 while it cannot be
    read)."""
    try:
        with h5py.File(path, "r", locking=False) as f:
            return int(np.isfinite(f["time"][()]).sum())
    except (OSError, KeyError):
        return 0
