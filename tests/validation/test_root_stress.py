"""The nominal blade root stress (pdfem/validation/cases/root_stress.py): beam theory on a
spinning bar with a tip load, mesh convergence on a propeller blade (``--quick``), and its
history in a run's results and ``pdfem post`` summary.

References: statics of a cantilever and the flexure formula, sigma = rho omega^2 L^2 / 2 +-
6 F L / (b h^2) (the cantilever-beam method of propeller blade strength); the project's
requirement that the blade root stress with 10-node blades agree within 5 % with a mesh
refined 2x; the radial stress of a bar spinning about its root at the root,
rho omega^2 R^2 / 2.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from pdfem.post.summary import summarize
from pdfem.validation import run_validation
from pdfem.validation.case import load_validation_case, run_and_read
from pdfem.validation.cases import root_stress


def test_quick_root_stress_cases_pass(tmp_path):
    """``pdfem validate --quick`` of the three cases: the bar's nominal root stress within 1 %
    of beam theory (39.81 and -20.19 MPa), the single blade's within 5 % of the mesh refined
    2x (about 1 s and 5 s)."""
    results = run_validation(root_stress.CASES, tmp_path, quick=True)
    failed = {r.name: (r.value, r.reference, r.message) for r in results if not r.passed}
    assert not failed, failed
    bar = {r.name: r for r in results}
    assert bar["bar_root_stress_tension"].reference == pytest.approx(39.8125e6, rel=1e-12)
    assert bar["bar_root_stress_compression"].reference == pytest.approx(-20.1875e6, rel=1e-12)
    assert bar["propeller_root_stress"].value < 0.05


def test_run_writes_the_root_stress_history_and_the_summary_reports_it(tmp_path):
    """spinning_bar_steady.toml (the bar at 100 rad/s from t = 0, no load) for a few steps:
    ``shaft/bar.blade1`` holds the nominal root stress every coupling step, all axial, at the
    root's rho omega^2 R^2 / 2 = 9.8125 MPa (the supports carry the centrifugal force of the
    lumped masses), and ``pdfem post``'s summary gives its peaks."""
    case = load_validation_case("spinning_bar_steady.toml")
    case = replace(case, run=replace(case.run, end_time=2.0e-5, output_interval=1.0e-5))
    data = run_and_read(case, tmp_path)
    h = data["histories"]["shaft/bar.blade1"]
    expected = 0.5 * 7850.0 * 100.0**2 * 0.5**2
    for key in ("root_stress_tension", "root_stress_compression", "root_stress_axial"):
        np.testing.assert_allclose(h[key], expected, rtol=1e-3, err_msg=key)
    peaks = summarize(data)["shaft"]["bar"]["blade"]["blade1"]["root_stress"]
    assert peaks["tension"]["value"] == pytest.approx(float(h["root_stress_tension"].max()))
    assert peaks["compression"]["value"] == pytest.approx(
        float(h["root_stress_compression"].min()))
