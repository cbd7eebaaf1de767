"""The command line: exit statuses, clear errors without tracebacks, JSON output, results files."""

from __future__ import annotations

import json

import h5py
import numpy as np

from support.cli import run_pdfem


def test_version_and_info_json():
    r = run_pdfem("--version")
    assert r.returncode == 0 and "pdfem" in r.stdout
    r = run_pdfem("info", "--json")
    assert r.returncode == 0
    info = json.loads(r.stdout)  # exactly one JSON object on stdout
    assert info["numba_threads"] >= 1 and "numpy" in info


def test_bad_case_exits_2_without_traceback(tmp_path):
    case = tmp_path / "bad.toml"
    case.write_text("[run]\nend_time = 1e-3\n[[ice]]\nname = 'a'\ndx = -1\n"
                    "shape = { box = { min = [0,0,0], max = [1,1,1] } }\n")
    r = run_pdfem("run", str(case), "--out", str(tmp_path / "o"))
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    assert "bad.toml" in r.stderr and "ice[0].dx" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1  # one paragraph


def test_missing_case_and_bad_arguments_exit_2(tmp_path):
    r = run_pdfem("run", str(tmp_path / "none.toml"))
    assert r.returncode == 2 and "no such case file" in r.stderr and "Traceback" not in r.stderr
    r = run_pdfem("frobnicate")
    assert r.returncode == 2 and "Traceback" not in r.stderr


def test_region_selecting_nothing_is_named(tmp_path):
    case = tmp_path / "empty_region.toml"
    case.write_text("[run]\nend_time = 1e-5\n[[ice]]\nname = 'a'\ndx = 0.01\n"
                    "shape = { box = { min = [0,0,0], max = [0.05,0.05,0.05] } }\n"
                    "fixed = [ { box = { min = [1,1,1], max = [2,2,2] } } ]\n")
    r = run_pdfem("run", str(case), "--out", str(tmp_path / "o"))
    assert r.returncode == 2 and "ice[0].fixed[0]" in r.stderr and "Traceback" not in r.stderr


def test_run_cli_json_summary(tmp_path):
    case = tmp_path / "tiny.toml"
    case.write_text("[run]\nend_time = 2e-5\noutput_interval = 1e-5\n[[ice]]\nname = 'cube'\ndx = 0.01\n"
                    "initial_velocity = [1, 0, 0]\n"
                    "shape = { box = { min = [0,0,0], max = [0.06,0.06,0.06] } }\n")
    r = run_pdfem("run", str(case), "--out", str(tmp_path / "o"), "--json")
    assert r.returncode == 0, r.stderr
    s = json.loads(r.stdout)
    assert s["particles"] == 216 and s["frames"] == 3
    # a free cube moving at 1 m/s: displacement = v t exactly (Galilean invariance, no internal force)
    with h5py.File(s["results"], "r") as f:
        u = f["ice/cube/u"][-1]
        t = f["time"][-1]
    np.testing.assert_allclose(u[:, 0], t * 1.0, rtol=1e-12)
