"""The Python interface (pdfem.api): load a case with overrides, run it, read its results.

References: the README's Python example, run as written; the results file read with h5py
directly (not pdfem's reader); linear elasticity (an elastic block pushed twice as fast carries
twice the reactions at every step); a fresh interpreter's module list (``import pdfem`` loads
none of pdfem's layers nor numpy).
"""

from __future__ import annotations

import contextlib
import io
import re
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

import pdfem
from pdfem.api import History, Results

from support.cases import BLOCK

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def block(tmp_path_factory) -> Path:
    """The tiny elastic block case (support.cases.BLOCK) as a file."""
    path = tmp_path_factory.mktemp("block") / "block.toml"
    path.write_text(BLOCK)
    return path


def test_the_readme_example_runs_and_prints_the_peak_load(tmp_path, monkeypatch):
    """The ```python block of README.md, executed as written from a folder that has models/."""
    code = re.search(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S).group(1)
    (tmp_path / "models").symlink_to(ROOT / "models")
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), {})
    printed = [float(x) for x in re.findall(r"([-+0-9.e]+) N", out.getvalue())]
    with h5py.File(tmp_path / "results" / "beam_fast" / "results.h5", "r") as f:
        t = f["loads/beam.nose/time"][...]
        force = f["loads/beam.nose/force"][...]
        case = f["meta"].attrs["case"]
    peak = np.abs(force[:, 2]).max()
    # the headline: |F| of the force averaged over 0.1 ms (whole steps), by convolution here
    n = min(len(t), round(1e-4 / (t[1] - t[0])))
    mean = np.stack([np.convolve(force[:, a], np.ones(n) / n, "valid") for a in range(3)], 1)
    assert peak > 0 and printed == [round(peak, 2)] * 2 + [
        round(np.linalg.norm(mean, axis=1).max(), 2)]
    assert "velocity = [0.0, 0.0, -0.04]" in case  # the override is in the stored case


def test_a_run_returns_its_histories_frames_and_summary_as_in_the_file(block, tmp_path):
    res = pdfem.run(block, out=tmp_path / "run")
    assert isinstance(res, Results) and res.run_summary.frames == 3
    assert sorted(res.regions) == ["block.base", "block.top"] and res.loads == {}
    with h5py.File(tmp_path / "run" / "results.h5", "r") as f:
        np.testing.assert_array_equal(res.time, f["time"][...])
        top = res.regions["block.top"]
        assert isinstance(top, History) and top.units == {"force": "N", "time": "s"}
        np.testing.assert_array_equal(top["force"], f["loads/block.top/force"][...])
        np.testing.assert_array_equal(top.time, f["loads/block.top/time"][...])
        np.testing.assert_array_equal(res.energy["residual"], f["energy/residual"][...])
        assert res.energy.units["residual"] == "J"
        last = res.frame(-1)["ice/block"]
        np.testing.assert_array_equal(last["u"], f["ice/block/u"][2])
        np.testing.assert_array_equal(last["x0"], f["ice/block/x0"][...])
        assert res.frame(1)["ice/block"]["damage"].shape == (216,)
    peak = res.summary["regions"]["block.top"]["magnitude"]["per_step_peak"]
    assert peak == pytest.approx(np.linalg.norm(top["force"], axis=1).max(), rel=1e-15)
    with pytest.raises(IndexError):
        res.frame(3)
    again = pdfem.open_results(tmp_path / "run")  # the folder, or the file
    np.testing.assert_array_equal(again.regions["block.base"]["force"],
                                  res.regions["block.base"]["force"])


def test_an_override_reaches_the_run_twice_the_push_twice_the_reactions(block, tmp_path):
    """Linear elasticity: the block is elastic and starts at rest, so pushing its top twice as
    fast doubles the reaction at every step (the time step does not depend on the speed), to
    the order of the strain: the bond stretch is geometrically exact, and the top moves
    v t = 20 um over the block's 6 cm, a strain of 3.3e-4 (measured: 2.0e-4 of the peak)."""
    slow = pdfem.run(pdfem.load_case(block), out=tmp_path / "slow")
    fast = pdfem.run(pdfem.load_case(block, overrides={
        "ice.0.prescribed_velocity.0.velocity": [0.0, 0.0, -1.0]}), out=tmp_path / "fast")
    for region in ("block.base", "block.top"):
        f1, f2 = slow.regions[region]["force"], fast.regions[region]["force"]
        assert np.abs(f1[:, 2]).max() > 100.0  # N: loaded
        np.testing.assert_allclose(f2, 2.0 * f1, rtol=0, atol=3.3e-4 * np.abs(f2).max())


def test_bad_input_raises_the_command_lines_error(block, tmp_path):
    with pytest.raises(pdfem.InputError) as e:
        pdfem.load_case(block, overrides={"ice.0.material.youngs_modulus": -1.0})
    assert e.value.field == "ice[0].material.youngs_modulus" and e.value.file == str(block)
    with pytest.raises(pdfem.InputError) as e:
        pdfem.load_case(block, overrides={"ice.1.dx": 0.02})
    assert e.value.field == "ice.1.dx"
    with pytest.raises(pdfem.InputError):
        pdfem.load_case(tmp_path / "missing.toml")
    with pytest.raises(pdfem.InputError):
        pdfem.open_results(tmp_path)  # no results.h5 there
    assert pdfem.InputError is pdfem.errors.InputError


def test_import_pdfem_is_cheap_and_pdfem_run_is_the_package_and_the_function():
    code = "import sys, pdfem; print(sorted(m for m in sys.modules if m.startswith(('pdfem', 'numpy'))))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, cwd=ROOT.parent)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["['pdfem',", "'pdfem.run']"]
    import pdfem.run.driver
    assert callable(pdfem.run) and pdfem.run.driver.run_case.__module__ == "pdfem.run.driver"


def test_a_sweep_from_python_validates_writes_its_job_array_and_collects(block, tmp_path):
    out = tmp_path / "study"
    script = pdfem.sweep(block, {"ice.0.material.youngs_modulus": np.array([3e9, 4e9])}, out,
                         slurm=True, quiet=True)
    assert script == out / "sweep.sbatch" and "#SBATCH --array=0-1\n" in script.read_text()
    assert (out / "runs" / "youngs_modulus=4e+09" / "case.toml").is_file()
    table = pdfem.collect(out)  # nothing has run: the runs without outputs, no plot
    assert [r["exit_status"] for r in table.rows] == [None, None] and table.plot is None
    assert table.columns == ["run", "ice.0.material.youngs_modulus", "exit_status"]
    with pytest.raises(pdfem.InputError) as e:
        pdfem.sweep(block, {"ice.0.dx": [0.01, -0.01]}, tmp_path / "bad", quiet=True)
    assert e.value.field == "--set ice.0.dx" and not (tmp_path / "bad").exists()
