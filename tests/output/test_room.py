"""Room on disk for results and checkpoint files (pdfem.output.room) under a real file-size
limit, in this process: ``RLIMIT_FSIZE`` lowered for the block (Python ignores SIGXFSZ, so a
write past it fails with EFBIG, as under ``ulimit -f``).

Reference: the frames written before the failure, read back as they were written; the
previous checkpoint file, read back unchanged. Before the reserve, the same write left a file
that did not open ("truncated file") and closing it crashed the process.
"""

from __future__ import annotations

import contextlib
import resource

import h5py
import numpy as np
import pytest

from pdfem.errors import OutputError
from pdfem.output import ResultsWriter, read_results
from pdfem.output.room import Room, write_atomically

N = 2000
"""Particles of the test body: a frame of u, v, damage is 112 kB, a chunk of u 8 frames."""


@contextlib.contextmanager
def file_size_limit(nbytes: int):
    """Files of this process cannot grow past ``nbytes`` while the block runs."""
    old = resource.getrlimit(resource.RLIMIT_FSIZE)
    resource.setrlimit(resource.RLIMIT_FSIZE, (nbytes, old[1]))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_FSIZE, old)


def _frame(k: int) -> dict:
    x = np.arange(3.0 * N).reshape(N, 3)
    return {"ice": {"u": x * k, "v": x + k, "damage": np.full(N, k / 100)}}


def _write_until_it_fails(path, limit: int) -> tuple[ResultsWriter, OutputError]:
    w = ResultsWriter(path, "case")
    w.add_ice_body("ice", np.zeros((N, 3)))
    with file_size_limit(limit), pytest.raises(OutputError) as err:
        for k in range(100):
            w.write_frame(1e-3 * k, _frame(k))
            w.append_history("energy", 1e-3 * k, {"e": k})
    return w, err.value


def test_results_writer_stops_whole_at_a_file_size_limit(tmp_path):
    """At a 3 MB limit the writer raises ``OutputError`` (naming the frame, EFBIG and the
    frames kept) before HDF5 writes past its last flush; the file then reads every frame
    written before, bit for bit, and nothing more is written to it."""
    path = tmp_path / "results.h5"
    w, err = _write_until_it_fails(path, 3_000_000)
    kept = w.n_frames
    assert 8 <= kept < 100
    assert f"writing frame {kept} (t = {1e-3 * kept:.6e} s) to {path} failed" in str(err)
    assert "EFBIG" in str(err) and f"keeps the {kept} frames written before" in str(err)
    with pytest.raises(OutputError):  # never again
        w.write_frame(1.0, _frame(1000))
    w.close()
    r = read_results(path)
    np.testing.assert_array_equal(r["time"], 1e-3 * np.arange(kept))
    for k in (0, kept - 1):
        for name, a in _frame(k)["ice"].items():
            np.testing.assert_array_equal(r["ice"]["ice"][name][k], a)
    assert r["histories"]["energy"]["e"].tolist() == list(range(kept - 1))  # rows to the last flush


def test_a_write_hdf5_fails_itself_is_released_without_a_crash(tmp_path, monkeypatch):
    """Without the reserve HDF5 itself meets the limit: the writer still raises
    ``OutputError`` (saying HDF5 failed part-way) and closing releases the file without
    another write: this process goes on (before: a segmentation fault on close)."""
    monkeypatch.setattr(Room, "ensure", lambda self, file, nbytes: None)
    monkeypatch.setattr(Room, "keep", lambda self, file: None)
    w, err = _write_until_it_fails(tmp_path / "results.h5", 3_000_000)
    assert "HDF5 failed part-way" in str(err) and "EFBIG" in str(err)
    w.close()
    w.close()


def test_a_failed_atomic_write_keeps_the_previous_file(tmp_path):
    """``write_atomically`` past a 1 MB limit: ``OutputError`` naming the temporary file, EFBIG
    and the bytes written; the temporary file is removed and the previous file at the path
    reads back unchanged."""
    path = tmp_path / "checkpoint.h5"
    write_atomically(path, lambda f: f.create_dataset("x", data=np.arange(10.0)), "v1")
    with file_size_limit(1_000_000), pytest.raises(OutputError) as err:
        write_atomically(path, lambda f: f.create_dataset("x", data=np.zeros(500_000)), "v2")
    text = str(err.value)
    assert text.startswith(f"writing v2 to {path}.tmp failed:") and "EFBIG" in text
    assert "bytes of it were written and removed again" in text
    assert sorted(p.name for p in tmp_path.iterdir()) == ["checkpoint.h5"]
    with h5py.File(path, "r") as f:
        np.testing.assert_array_equal(f["x"][()], np.arange(10.0))
