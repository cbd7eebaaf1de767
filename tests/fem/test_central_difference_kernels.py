"""The central-difference step's work pass (:func:`trapezoid_work`) against the vector formula.

Reference: the trapezoidal rule's work ``1/2 (f0 + f1) . du`` of a force over a step, with
``du`` the increment or the difference of two displacements, by numpy (other summation order:
equal to round-off).
"""

import numpy as np
import pytest

from pdfem.fem.central_difference_kernels import NO_OFFSET, trapezoid_work


@pytest.mark.parametrize("n", [0, 1, 3, 4, 7, 14967])
def test_trapezoid_work_is_the_trapezoidal_rule(n):
    rng = np.random.default_rng(n)
    f0, f1, u1, u0 = rng.standard_normal((4, n))
    scale = 1.0 + np.abs(f0 + f1) @ (np.abs(u1) + np.abs(u0))
    assert abs(trapezoid_work(f0, f1, u1, NO_OFFSET) - 0.5 * (f0 + f1) @ u1) <= 1e-14 * scale
    assert abs(trapezoid_work(f0, f1, u1, u0) - 0.5 * (f0 + f1) @ (u1 - u0)) <= 1e-14 * scale
