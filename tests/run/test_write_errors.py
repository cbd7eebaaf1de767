"""Write errors of a run (pdfem.output.room): a file-size limit, no space left or an I/O error
while results or checkpoints are written end the run with exit 1 and one paragraph, no
traceback, and leave the results written so far readable and the previous checkpoint whole.

Reference: what the files held before the failure (the frames of the run up to then, the
checkpoint written before), read back with h5py and pdfem's reader. ENOSPC and EIO are
simulated in-process at the system call or HDF5 call that would meet them; the file-size limit
is real (``RLIMIT_FSIZE`` in a subprocess, as ``ulimit -f`` sets it).
"""

from __future__ import annotations

import errno
import resource
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest

from pdfem.output import read_results
from pdfem.output.room import NoRoom, Room
from pdfem.run import checkpoint_ranks
from pdfem.run.checkpoint import CHECKPOINT_NAME, read_checkpoint

from support.cases import TWO_CUBES
from support.cli import pdfem_command, run_main

LIMIT = 3_000_000
"""File-size limit (bytes) of the subprocess: with a frame every 2.5e-5 s the 161 frames of
TWO_CUBES (positions ``x`` included) take 4.9 MB, so the limit stops the run part-way."""


@pytest.fixture(scope="module")
def case_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("write_errors") / "case.toml"
    path.write_text(TWO_CUBES)
    return path


def _one_paragraph(stderr: str) -> str:
    """The run's error message: one paragraph, no traceback."""
    assert "Traceback" not in stderr, stderr
    text = stderr.strip()
    assert text.startswith("pdfem: writing ") and "\n" not in text, stderr
    return text


def test_file_size_limit_ends_the_run_with_its_results_readable(case_file, tmp_path):
    """Under ``ulimit -f`` (RLIMIT_FSIZE of 3 MB) the run exits 1 with one paragraph naming
    the limit, no traceback and no crash (before: three chained tracebacks, then a
    segmentation fault, exit 139), and ``results.h5`` opens with h5py and reads the frames the
    message says it keeps (before: the file did not open)."""
    out = tmp_path / "limited"
    case = tmp_path / "case.toml"
    case.write_text(case_file.read_text().replace("output_interval = 5.0e-4",
                                                  "output_interval = 2.5e-5"))

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (LIMIT, LIMIT))

    r = subprocess.run([*pdfem_command(), "run", str(case), "--out", str(out), "--quiet"],
                       capture_output=True, text=True, timeout=600, preexec_fn=limit)
    assert r.returncode == 1, r.stderr[-3000:]
    text = _one_paragraph(r.stderr)
    assert f"file-size limit ({LIMIT:,} bytes, ulimit -f; EFBIG)" in text
    with h5py.File(out / "results.h5", "r") as f:
        assert "meta" in f
    kept = read_results(out / "results.h5")
    frames = kept["time"]
    assert (out / "results.h5").stat().st_size <= LIMIT
    # reference: the same run without the limit (deterministic): the kept frames are its first
    # ones, the same bits, and the limit stopped the run part-way
    r = subprocess.run([*pdfem_command(), "run", str(case), "--out", str(tmp_path / "whole"),
                        "--quiet"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    whole = read_results(tmp_path / "whole" / "results.h5")
    assert whole["time"].size == round(4.0e-3 / 2.5e-5) + 1   # 161 frames to end_time
    assert 2 <= frames.size < whole["time"].size
    assert np.array_equal(frames, whole["time"][:frames.size])
    for body in ("a", "b"):
        for field in ("x", "v", "damage"):
            assert np.array_equal(kept["ice"][body][field],
                                  whole["ice"][body][field][:frames.size]), (body, field)
    assert f"keeps the {frames.size} frames written before (to t = {frames[-1]:.6e} s)" in text


def test_no_space_left_after_the_first_frame(case_file, tmp_path, monkeypatch):
    """ENOSPC at the first reserve once the file holds its first frame: exit 1, one paragraph
    (what, file, cause), and the file holds the first frame, whole."""
    ensure = Room.ensure

    def full_disk(self, file, nbytes):
        if file.id.get_filesize() > 1_000_000:  # past the first frame
            raise NoRoom(errno.ENOSPC, "No space left on device")
        ensure(self, file, nbytes)

    monkeypatch.setattr(Room, "ensure", full_disk)
    out = tmp_path / "full"
    r = run_main("run", case_file, "--out", out, "--quiet")
    assert r.returncode == 1
    text = _one_paragraph(r.stderr)
    assert f"to {out / 'results.h5'} failed: no space is left on the device" in text
    assert "ENOSPC" in text and "keeps the 1 frame written before (to t = 0.000000e+00 s)" in text
    assert read_results(out / "results.h5")["time"].tolist() == [0.0]


def test_input_output_error_inside_hdf5(case_file, tmp_path, monkeypatch):
    """An I/O error HDF5 meets flushing the third frame: exit 1, one paragraph naming EIO; the
    file is released without another write (no crash), and reads its first two frames."""
    flush, calls = h5py.File.flush, []

    def failing_flush(self):
        calls.append(self.filename)
        if len(calls) == 10:  # the first flush of the third frame (after the XDMF padding's)
            raise RuntimeError("Unable to synchronously flush file (file write failed: "
                               "errno = 5, error message = 'Input/output error')")
        flush(self)

    monkeypatch.setattr(h5py.File, "flush", failing_flush)
    out = tmp_path / "eio"
    r = run_main("run", case_file, "--out", out, "--quiet")
    assert r.returncode == 1
    text = _one_paragraph(r.stderr)
    assert "input/output error (EIO)" in text and "HDF5 failed part-way" in text
    assert read_results(out / "results.h5")["time"].size == 2


def test_no_space_left_for_a_checkpoint(case_file, tmp_path, monkeypatch):
    """ENOSPC while the second checkpoint's part is written: exit 1, one paragraph naming the
    part, the bytes written and the previous checkpoint (step 100), which stays whole and
    readable, with no temporary file left; the results so far read."""
    write_part, calls = checkpoint_ranks.write_part, []

    def full_disk(f, bodies, forces):
        calls.append(1)
        write_part(f, bodies, forces)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(checkpoint_ranks, "write_part", full_disk)
    text = case_file.read_text().replace("short_range_contact = true",
                                         "short_range_contact = true\ncheckpoint_interval_steps = 100")
    case = tmp_path / "case.toml"
    case.write_text(text)
    out = tmp_path / "out"
    r = run_main("run", case, "--out", out, "--quiet")
    assert r.returncode == 1
    message = _one_paragraph(r.stderr)
    assert "writing the checkpoint part of rank 0 to" in message and "ENOSPC" in message
    assert "bytes of it were written and removed again" in message
    assert f"previous checkpoint {out / CHECKPOINT_NAME} (step 100) is kept" in message
    assert sorted(p.name for p in out.glob("checkpoint*")) == ["checkpoint.g100.rank0.h5",
                                                               CHECKPOINT_NAME]
    assert read_checkpoint(out / CHECKPOINT_NAME, text, str(case)).driver.step == 100
    assert read_results(out / "results.h5")["time"].size == 2  # to step 198
