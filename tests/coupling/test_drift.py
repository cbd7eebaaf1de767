"""The ice's drift over a structure substep (:func:`pdfem.coupling.drift.drift`).

Reference: the numpy expressions it replaced, ``before = y.copy(); u = v + kick * c;
y += h * u`` (and ``y += h * v`` without a kick), bit for bit, threaded and on one thread: runs keep their results.
"""

from __future__ import annotations

import numpy as np
import pytest

from pdfem.coupling.drift import drift


@pytest.mark.parametrize("parallel", [False, True])
def test_drift_with_kick_is_numpy_s_bits(parallel):
    rng = np.random.default_rng(5)
    y, v, kick = (rng.normal(size=(1000, 3)) for _ in range(3))
    c, h = (2 * 3 + 1) / 7 - 1.0, 1.3e-6
    before, u = np.empty_like(y), np.empty_like(y)
    y_ref = y.copy()
    u_ref = v + kick * c
    y_ref += h * u_ref
    yy = y.copy()
    drift(parallel, yy, v, kick, c, h, before, u, True, True)
    assert np.array_equal(before, y) and np.array_equal(u, u_ref) and np.array_equal(yy, y_ref)


@pytest.mark.parametrize("parallel", [False, True])
def test_drift_without_kick_moves_by_v_and_leaves_the_buffers(parallel):
    rng = np.random.default_rng(6)
    y, v = rng.normal(size=(500, 3)), rng.normal(size=(500, 3))
    y_ref = y.copy()
    y_ref += 2e-6 * v
    untouched = np.full_like(y, 7.0)
    drift(parallel, y, v, v, 0.0, 2e-6, untouched, untouched, False, False)
    assert np.array_equal(y, y_ref) and np.all(untouched == 7.0)
