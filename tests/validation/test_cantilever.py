"""The cantilever validation entries (``models/validation/cantilever_frequency.toml``, explicit,
and ``cantilever_frequency_implicit.toml``, implicit Newmark; quick variant: three periods of the
first mode) checked against their reference and, more tightly, against the FE model's own first
eigenfrequency.

References: Euler-Bernoulli beam theory, f1 = 1.875104^2 / (2 pi L^2) sqrt(E I / (rho A)) (the
entry's reference and tolerance, 3 %); the lowest eigenvalue of the model's constrained
``M^-1 K`` (scipy eigsh), which the runs must reproduce: the spectral peak within 1 %,
the period from the zero crossings about the static deflection within 0.5 %.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse.linalg as sla

from pdfem.run.build_structures import build_all
from pdfem.validation import all_cases
from pdfem.validation.case import Outcome, case_path, load_validation_case


@pytest.mark.parametrize("name", [
    pytest.param("cantilever_frequency", marks=pytest.mark.slow),
    "cantilever_frequency_implicit", "cantilever_frequency_implicit_large_step"])
def test_quick_cantilever_frequency_is_the_beam_s_and_the_fe_model_s(tmp_path, name):
    """The quick entry passes (Euler-Bernoulli, 3 %; at 10 implicit steps per period as the
    average-acceleration rule carries it, (2/dt) atan(w dt/2)); its spectral peak is within 1 %
    and its zero-crossing period within 0.5 % of the FE model's first eigenfrequency (carried
    the same way for the implicit runs): explicit at the elements' stable step, implicit
    (Newmark) at 100 and at 10 steps per period."""
    entry = next(c for c in all_cases() if c.name == name)
    run = entry.quick(load_validation_case(entry.case_file))
    outcome = Outcome(run, entry.execute(run, tmp_path / "run"), tmp_path / "run", 0.0)
    value, reference = entry.measure(outcome), entry.reference(run)
    assert entry.error(value, reference) <= entry.tolerance, (value, reference)

    with case_path(entry.case_file) as path:
        beam = build_all(run.structures, tmp_path / "mesh", str(path))[0]
    free = beam.solver.free
    d = 1.0 / np.sqrt(beam.mass[free])
    stiffness = beam.K[free][:, free]
    scaled = stiffness.multiply(d[:, None]).multiply(d[None, :]).tocsc()
    lam1 = sla.eigsh(scaled, k=1, sigma=0.0, which="LM", return_eigenvectors=False)[0]
    f_fe = math.sqrt(lam1) / (2.0 * math.pi)
    if run.structures[0].integrator == "implicit":   # the trapezoidal rule's own frequency
        dt = run.run.time_step
        f_fe = 2.0 / dt * math.atan(0.5 * math.sqrt(lam1) * dt) / (2.0 * math.pi)

    # the static deflection the tip swings about (the held load, K u = f)
    f = beam.external_force_dofs()
    u = np.zeros_like(f)
    u[free] = sla.spsolve(stiffness.tocsc(), f[free])
    tip = run.monitors[0].point
    node = int(np.argmin(np.linalg.norm(beam.node_points - np.asarray(tip), axis=1)))
    w_static = u[beam.dofmap.nodal_dofs[2, node]]

    h = outcome.data["histories"]["monitors/tip"]
    t, w = h["time"], h["u"][:, 2] - w_static
    i = np.flatnonzero(np.sign(w[:-1]) != np.sign(w[1:]))
    crossings = t[i] - w[i] * (t[i + 1] - t[i]) / (w[i + 1] - w[i])
    assert len(crossings) >= 5
    f_zero = (len(crossings) - 1) / (2.0 * (crossings[-1] - crossings[0]))
    print(f"f1: spectral peak {value:.3f} Hz, zero crossings {f_zero:.3f} Hz, "
          f"FE eigsh {f_fe:.3f} Hz, Euler-Bernoulli {reference:.3f} Hz")
    assert f_zero == pytest.approx(f_fe, rel=0.005)
    assert value == pytest.approx(f_fe, rel=0.01)
