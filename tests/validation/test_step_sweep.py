"""The built-in demo at several coupling steps (``pdfem validate`` entries of
:mod:`pdfem.validation.cases.coupled_step`, ``--quick``: to 2.5 ms, impact and peak load).

At safety factors 0.9, 0.6, 0.3 and 0.15 with automatic substeps and at 0.6 with 1 and 2
substeps: the energy balance closes within 1 % of the energy supplied at every frame
(conservation of energy), no dissipation term is ever negative beyond round-off (second
law), and the peak ice load averaged over 0.1 ms agrees within 5 % with the run at 0.9
(time-step convergence). Its own file so that this six-run sweep, the longest of the quick
validation runs, runs beside the others.
"""

from __future__ import annotations

import pytest

from pdfem.validation.cases import coupled_step
from pdfem.validation.runner import run_validation


@pytest.mark.slow
def test_quick_step_sweep_passes(tmp_path):
    results = run_validation(list(coupled_step.CASES), tmp_path, quick=True)
    assert [r.name for r in results] == ["step_energy_residual", "step_dissipation_sign",
                                         "step_load_convergence"]
    failed = {r.name: (r.value, r.tolerance, r.message) for r in results if not r.passed}
    assert not failed, failed
