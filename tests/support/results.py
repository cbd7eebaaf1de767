"""Results files in tests: a small hand-made one for the tests of ``pdfem post``
(:func:`write_swinging_monitor`), comparing two runs' results files array by array, bit for bit
(:func:`assert_same_results`, the reference of every restart test: the uninterrupted run), and
counting the frames a running run has committed (:func:`committed_frames`, for tests that act
on a run mid-way).
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from pdfem.output import ResultsWriter, read_results


def write_swinging_monitor(path: Path, title: str = "fatigue") -> Path:
    """Write ``path``: one elastic tetrahedron 'panel' at rest and a monitor 'root' whose xx
    stress swings 40 MPa +- 50 MPa, 10 cycles over 21 steps of 1 ms; returns ``path``."""
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    with ResultsWriter(path, "", {"title": title}) as w:
        w.add_structure("panel", points, np.array([[0, 1, 2, 3]]), "tetra")
        w.write_frame(0.0, {}, {"panel": {"u": np.zeros((4, 3)), "von_mises": np.zeros(1)}})
        for k in range(21):
            sxx = 40e6 + 50e6 * (-1.0) ** k
            w.append_history("monitors/root", k * 1e-3, {
                "u": [0.0, 0.0, 0.0], "von_mises": abs(sxx),
                "stress": [sxx, 0.0, 0.0, 0.0, 0.0, 0.0]})
    return path

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
