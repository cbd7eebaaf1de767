"""Checkpoints and restart: a run killed with SIGKILL and restarted from its last checkpoint
ends bit for bit where the uninterrupted run ends.

Reference: the uninterrupted run of the same case (same machine, same threads; the pair kernels
are deterministic). The case couples every part of the state: an ice cube (bonds breaking,
short-range contact) strikes an elastic steel block clamped at its base, with friction, so ice
state, structure state, pending contact loads and contact work counters must all be restored.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from pdfem.run.checkpoint import CHECKPOINT_NAME
from pdfem.case.schema import load_case
from pdfem.run.driver import run_case
from pdfem.output import ResultsWriter, read_results

from support.cli import pdfem_command, run_ok, run_pdfem

CASE = """
[run]
end_time = 1.2e-3
output_interval = 1e-4
checkpoint_interval_steps = 40
short_range_contact = true

[[ice]]
name = "cube"
dx = 0.01
shape = { box = { min = [0.07, 0.07, 0.0355], max = [0.13, 0.13, 0.0955] } }
material = { density = 900.0, youngs_modulus = 4.1e9, poisson_ratio = 0.3, fracture_energy = 1.0 }
initial_velocity = [0.0, 0.0, -3.0]

[[structure]]
name = "block"
mesh = "block.msh"
material = { density = 7850.0, youngs_modulus = 210e9, poisson_ratio = 0.3 }
fixed_groups = ["fixed"]
contact_group = "contact"

[[contact]]
ice = "cube"
structure = "block"
friction = 0.1
"""


def _checkpoint_step(path: Path) -> int:
    try:
        with h5py.File(path, "r") as f:
            return int(f["driver"].attrs["step"])
    except (OSError, KeyError):
        return -1


def _datasets(path: Path) -> dict[str, np.ndarray]:
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                out[name] = obj[()]
            for k, v in obj.attrs.items():
                out[f"{name}@{k}"] = v
        f.visititems(visit)
    return out


@pytest.fixture(scope="module")
def case_dir(tmp_path_factory, gmsh_box):
    d = tmp_path_factory.mktemp("ckpt")
    gmsh_box(d / "block.msh", (0.2, 0.2, 0.04), face_groups={"fixed": ["z0"], "contact": ["z1"]},
             divisions=(5, 5, 2))
    (d / "case.toml").write_text(CASE)
    return d


@pytest.mark.slow
def test_killed_run_restarts_bit_identical(case_dir):
    """SIGKILL after a checkpoint, then ``pdfem run --restart``: the final frame (ice u, v,
    damage; structure u), the whole load and energy histories, and the last checkpoint's full
    state (ice y, v, f, broken, theta; structure u, v, a, ...; coupler) equal those of the
    uninterrupted run bit for bit."""
    case = load_case(case_dir / "case.toml")
    ref = run_case(case, case_dir / "ref", quiet=True)
    killed = case_dir / "killed"
    proc = subprocess.Popen([*pdfem_command(), "run", str(case_dir / "case.toml"), "--out", str(killed),
                             "--quiet"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 300
    while _checkpoint_step(killed / CHECKPOINT_NAME) < 80 and proc.poll() is None:
        assert time.monotonic() < deadline, "no checkpoint appeared"
        time.sleep(0.02)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the run finished before it could be killed"
    ckpt_step = _checkpoint_step(killed / CHECKPOINT_NAME)
    assert 80 <= ckpt_step < ref.steps
    before = read_results(killed / "results.h5")  # the killed run's file reads
    assert before["time"].size >= 1

    run_ok("run", case_dir / "case.toml", "--restart", killed / CHECKPOINT_NAME, "--json", timeout=600)
    a, b = read_results(ref.results), read_results(killed / "results.h5")
    np.testing.assert_array_equal(a["time"], b["time"])
    for k in ("u", "v", "damage"):
        np.testing.assert_array_equal(a["ice"]["cube"][k], b["ice"]["cube"][k])
    np.testing.assert_array_equal(a["structure"]["block"]["u"], b["structure"]["block"]["u"])
    assert a["ice"]["cube"]["damage"][-1].max() > 0  # bonds broke: the broken flags matter
    assert np.abs(a["structure"]["block"]["u"][-1]).max() > 0  # the block was struck
    assert sorted(a["histories"]) == sorted(b["histories"])
    for g, hist in a["histories"].items():
        assert sorted(hist) == sorted(b["histories"][g])
        for k, v in hist.items():
            np.testing.assert_array_equal(v, b["histories"][g][k], err_msg=f"{g}/{k}")
    assert np.abs(a["histories"]["loads/block"]["force"]).max() > 0
    sa, sb = _datasets(ref.results.parent / CHECKPOINT_NAME), _datasets(killed / CHECKPOINT_NAME)
    assert sorted(sa) == sorted(sb)
    for k in sa:
        np.testing.assert_array_equal(sa[k], sb[k], err_msg=k)
    # the XDMF file names every frame once, in each grid (ice, the block's contact surface, block)
    xdmf = (killed / "results.xdmf").read_text()
    assert xdmf.count('<Time Value=') == 3 * len(a["time"])
    np.testing.assert_array_equal(a["structure"]["block.contact"]["contact_pressure"],
                                  b["structure"]["block.contact"]["contact_pressure"])


def _assert_same_run(a: dict, b: dict, exact: bool = True) -> None:
    """Every frame and history of two results files equal (bit for bit, or to 1e-10)."""
    same = (np.testing.assert_array_equal if exact else
            lambda x, y, err_msg="": np.testing.assert_allclose(
                x, y, rtol=1e-10, atol=1e-10 * max(np.abs(x).max(initial=0.0), 1e-300),
                err_msg=err_msg))
    np.testing.assert_array_equal(a["time"], b["time"])
    for k in ("u", "v"):
        same(a["ice"]["cube"][k], b["ice"]["cube"][k], err_msg=k)
    np.testing.assert_array_equal(a["ice"]["cube"]["damage"], b["ice"]["cube"]["damage"])
    same(a["structure"]["block"]["u"], b["structure"]["block"]["u"], err_msg="block u")
    for g in ("loads/block", "energy"):
        for k, v in a["histories"][g].items():
            same(v, b["histories"][g][k], err_msg=f"{g}/{k}")


@pytest.mark.slow
def test_killed_mpi_run_restarts_bit_identical(case_dir):
    """On 2 MPI ranks (short-range contact across the ranks included): SIGKILL of the whole
    job after a checkpoint, then ``mpiexec -n 2 pdfem
    run --restart``: every frame and history equals the uninterrupted 2-rank run bit for bit.
    The same checkpoint restarted on 1 rank agrees with it to round-off (1e-10): the ranks'
    checkpoint parts name their particles and bonds by global numbers, so any rank count reads
    them."""
    mpi = [*pdfem_command(2), "run", str(case_dir / "case.toml")]
    ref = case_dir / "mpi_ref"
    r = subprocess.run([*mpi, "--out", str(ref), "--quiet"], capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    killed = case_dir / "mpi_killed"
    proc = subprocess.Popen([*mpi, "--out", str(killed), "--quiet"], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.monotonic() + 300
    while _checkpoint_step(killed / CHECKPOINT_NAME) < 80 and proc.poll() is None:
        assert time.monotonic() < deadline, "no checkpoint appeared"
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGKILL)  # mpiexec and both ranks at once
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, "the run finished before it could be killed"
    ckpt_step = _checkpoint_step(killed / CHECKPOINT_NAME)
    assert 80 <= ckpt_step < 120
    assert read_results(killed / "results.h5")["time"].size >= 1  # the killed run's file reads
    serial = case_dir / "mpi_killed_serial"
    shutil.copytree(killed, serial)

    r = subprocess.run([*mpi, "--restart", str(killed / CHECKPOINT_NAME), "--quiet"],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    a, b = read_results(ref / "results.h5"), read_results(killed / "results.h5")
    assert a["ice"]["cube"]["damage"][-1].max() > 0  # bonds broke: the broken flags matter
    assert np.abs(a["histories"]["loads/block"]["force"]).max() > 0
    _assert_same_run(a, b)
    assert sorted(a["histories"]) == sorted(b["histories"])
    sa, sb = _datasets(ref / CHECKPOINT_NAME), _datasets(killed / CHECKPOINT_NAME)
    assert sorted(sa) == sorted(sb)
    for k in sa:
        np.testing.assert_array_equal(sa[k], sb[k], err_msg=k)

    r = run_ok("run", case_dir / "case.toml", "--restart", serial / CHECKPOINT_NAME, "--quiet", timeout=600)
    _assert_same_run(a, read_results(serial / "results.h5"), exact=False)


def test_restart_refuses_another_case(case_dir, tmp_path):
    """A checkpoint stores the SHA-256 of its case text: a changed case is refused (exit 2)."""
    out = case_dir / "ref"
    if not (out / CHECKPOINT_NAME).exists():
        run_case(load_case(case_dir / "case.toml"), out, quiet=True)
    other = case_dir / "other.toml"
    other.write_text(CASE.replace("friction = 0.1", "friction = 0.2"))
    r = run_pdfem("run", other, "--restart", out / CHECKPOINT_NAME, timeout=600)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "another case" in r.stderr and "--restart" in r.stderr
    r = run_pdfem("run", other, "--restart", tmp_path / "none.h5", timeout=600)
    assert r.returncode == 2 and "no such checkpoint" in r.stderr


def test_results_writer_resume_drops_later_frames_and_rows(tmp_path):
    """Append mode keeps exactly the frames and history rows named, then continues: the file
    equals one written straight through with the same rows (reference: the direct write)."""
    x0 = np.arange(12.0).reshape(4, 3)

    def fields(t):
        return {"a": {"u": x0 * t, "v": x0 + t, "damage": np.full(4, t)}}

    straight = tmp_path / "straight.h5"
    with ResultsWriter(straight, "case") as w:
        w.add_ice_body("a", x0)
        for k in range(5):
            w.write_frame(float(k), fields(k))
            w.append_history("energy", float(k), {"e": k})
    resumed = tmp_path / "resumed.h5"
    with ResultsWriter(resumed, "case") as w:
        w.add_ice_body("a", x0)
        for k in range(4):
            w.write_frame(float(k), fields(k + 100 if k == 3 else k))  # frame 3: to be dropped
            w.append_history("energy", float(k), {"e": k if k < 3 else -1})
            w.append_history("later", float(k), {"x": k})
    with pytest.raises(ValueError, match="another case"):
        ResultsWriter(resumed, "other case", append=True)
    with ResultsWriter(resumed, "case", append=True) as w:
        w.add_ice_body("a", x0)
        w.resume(3, {"energy": 3})
        for k in (3, 4):
            w.write_frame(float(k), fields(k))
            w.append_history("energy", float(k), {"e": k})
    a, b = read_results(straight), read_results(resumed)
    np.testing.assert_array_equal(a["time"], b["time"])
    for k in ("u", "v", "damage"):
        np.testing.assert_array_equal(a["ice"]["a"][k], b["ice"]["a"][k])
    assert sorted(b["histories"]) == ["energy"]
    np.testing.assert_array_equal(a["histories"]["energy"]["e"], b["histories"]["energy"]["e"])
    assert resumed.with_suffix(".xdmf").read_text().count("<Time Value=") == 5
