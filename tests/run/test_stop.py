"""Stopping a run on a signal (pdfem.run.stop): SIGTERM mid-way ends the run at a coupling step
with a checkpoint and a last frame, exit status 4 and the restart command; the restart ends bit
for bit where the uninterrupted run ends.

Reference: the uninterrupted run of the same case (same machine; the pair kernels are
deterministic). The case (``TWO_CUBES``, tests/support/cases.py) makes the restart carry
broken bonds and contact state: two ice cubes meet at 4 m/s with short-range contact and break
about half their bonds.
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import h5py
import pytest

from pdfem.case.schema import load_case
from pdfem.errors import EXIT_STOPPED
from pdfem.run.checkpoint import CHECKPOINT_NAME
from pdfem.run.driver import run_case
from pdfem.run.stop import StopRequest, stop_signals

from support.cases import TWO_CUBES
from support.cli import pdfem_command, run_main
from support.results import assert_same_results, committed_frames

STEPS = 1583
"""Coupling steps of TWO_CUBES (a step of 2.527e-6 s to 4 ms)."""


@pytest.fixture(scope="module")
def case_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("stop") / "case.toml"
    path.write_text(TWO_CUBES)
    return path


def _signal_mid_way(command: list, out: Path, send) -> subprocess.CompletedProcess:
    """Start ``command --out out``, wait until its results hold 2 frames, call ``send(proc)``
    and wait for the end."""
    proc = subprocess.Popen([*command, "--out", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    deadline = time.monotonic() + 300
    while committed_frames(out / "results.h5") < 2 and proc.poll() is None:
        assert time.monotonic() < deadline, "no frame appeared"
        time.sleep(0.01)
    send(proc)
    stdout, stderr = proc.communicate(timeout=300)
    return subprocess.CompletedProcess(command, proc.returncode, stdout, stderr)


def _checkpoint_step(path: Path) -> int:
    with h5py.File(path, "r") as f:
        return int(f["driver"].attrs["step"])


def test_sigterm_stops_with_a_checkpoint_and_restarts_bit_identical(case_file, tmp_path):
    """SIGTERM once 2 frames are written: exit 4, no traceback, the message names the
    checkpoint and the restart command; the checkpoint is at the stop step, mid-way; the
    results hold a last frame at the stop; ``--restart`` then ends bit for bit like the
    uninterrupted run (every frame and history)."""
    ref = run_case(load_case(case_file), tmp_path / "ref", quiet=True)
    out = tmp_path / "stopped"
    r = _signal_mid_way([*pdfem_command(), "run", str(case_file)], out,
                        lambda p: p.send_signal(signal.SIGTERM))
    assert r.returncode == EXIT_STOPPED, r.stderr[-3000:]
    assert "Traceback" not in r.stderr
    ckpt = out / CHECKPOINT_NAME
    assert "stopped by SIGTERM" in r.stderr and str(ckpt) in r.stderr
    assert f"--restart {ckpt}" in r.stderr and f"--out {out}" in r.stderr
    step = _checkpoint_step(ckpt)
    assert 198 <= step < STEPS  # after the frame at t = 5e-4 s (step 198), before the end
    with h5py.File(out / "results.h5", "r") as f:  # the last frame is the state at the stop
        assert f["time"][-1] == pytest.approx(step * ref.time_step, rel=1e-12)
    r = run_main("run", case_file, "--out", out, "--restart", ckpt, "--quiet")
    assert r.returncode == 0, r.stderr
    assert_same_results(ref.results, out / "results.h5")


def _rank_pids(out: Path) -> dict[int, int]:
    """The process ids of the MPI ranks running ``pdfem run ... --out out``, by rank (read
    from /proc: their command line and their launcher's ``PMI_RANK``)."""
    pids = {}
    for entry in Path("/proc").iterdir():
        try:
            cmd = (entry / "cmdline").read_bytes().split(b"\0")
            env = (entry / "environ").read_bytes().split(b"\0")
        except (OSError, ValueError):
            continue
        rank = [v[len(b"PMI_RANK="):] for v in env if v.startswith(b"PMI_RANK=")]
        if str(out).encode() in cmd and rank and not any(b"mpiexec" in c for c in cmd):
            pids[int(rank[0])] = int(entry.name)
    return pids


@pytest.mark.slow
def test_sigterm_to_one_rank_stops_every_rank_at_the_same_step(case_file, tmp_path):
    """On 2 ranks, SIGTERM to rank 1 alone (as a signal may reach only some ranks): both ranks
    stop at the same step (one checkpoint set, exit 4 from mpiexec), and the 2-rank restart
    ends bit for bit like the uninterrupted 2-rank run."""
    mpi = [*pdfem_command(2), "run", str(case_file)]
    r = subprocess.run([*mpi, "--out", str(tmp_path / "ref"), "--quiet"], capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    out = tmp_path / "stopped"

    def to_rank_1(proc):
        pids = _rank_pids(out)
        assert sorted(pids) == [0, 1], pids
        os.kill(pids[1], signal.SIGTERM)

    r = _signal_mid_way(mpi, out, to_rank_1)
    assert r.returncode == EXIT_STOPPED, r.stderr[-3000:]
    assert "Traceback" not in r.stderr and "stopped by SIGTERM" in r.stderr
    assert "mpiexec -n 2 pdfem run" in r.stderr
    ckpt = out / CHECKPOINT_NAME
    step = _checkpoint_step(ckpt)
    assert 198 <= step < STEPS
    assert sorted(p.name for p in out.glob("checkpoint.g*")) == [
        f"checkpoint.g{step}.rank0.h5", f"checkpoint.g{step}.rank1.h5"]
    r = subprocess.run([*mpi, "--out", str(out), "--restart", str(ckpt), "--quiet"],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    assert_same_results(tmp_path / "ref" / "results.h5", out / "results.h5")


def test_a_second_sigint_stops_at_once_and_handlers_are_restored():
    """The first SIGINT (or SIGTERM, SIGUSR1) only asks for a stop; a second SIGINT raises
    ``KeyboardInterrupt`` at once. ``stop_signals`` installs the handler for the run only and
    puts the previous handlers back."""
    stop = StopRequest()
    stop.handle(signal.SIGINT)
    assert stop.signal == signal.SIGINT and stop.name == "SIGINT"
    with pytest.raises(KeyboardInterrupt):
        stop.handle(signal.SIGINT)
    stop = StopRequest()
    stop.handle(signal.SIGUSR1)
    stop.handle(signal.SIGTERM)
    assert stop.name == "SIGUSR1"  # the first signal is the one reported
    before = {s: signal.getsignal(s) for s in (signal.SIGTERM, signal.SIGUSR1, signal.SIGINT)}
    with stop_signals() as stop:
        os.kill(os.getpid(), signal.SIGUSR1)
        assert stop.name == "SIGUSR1"
        assert signal.getsignal(signal.SIGTERM) == stop.handle
    assert {s: signal.getsignal(s) for s in before} == before


def test_sigterm_still_stops_after_gmsh_meshed_a_structure():
    """gmsh's library installs its own SIGTERM handler (it prints "Terminated" and exits 143),
    behind Python's back; a gmsh session puts Python's back when it ends, so a run whose
    structure was meshed by a model script still stops with a checkpoint (before: the demo
    died at once with status 143)."""
    from pdfem.meshing import gmsh_session

    with stop_signals() as stop:
        with gmsh_session("box") as gmsh:
            gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        os.kill(os.getpid(), signal.SIGTERM)
        assert stop.name == "SIGTERM"
