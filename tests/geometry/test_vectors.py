"""``pdfem.geometry.vectors.cross`` is ``numpy.cross`` for 3-vectors, bit for bit.

Reference: ``numpy.cross`` on the same arrays, every broadcasting the steps use ((3,) with
(3,) and (N, 3), (N, 3) with (N, 3) and (3,), stacked (M, N, 3)).
"""

from __future__ import annotations

import numpy as np
import pytest

from pdfem.geometry.vectors import cross, resultant


@pytest.mark.parametrize("sa, sb", [((3,), (3,)), ((3,), (50, 3)), ((50, 3), (50, 3)),
                                    ((50, 3), (3,)), ((4, 7, 3), (4, 7, 3)), ((1, 3), (5, 3))])
def test_same_bits_as_numpy_cross(sa, sb):
    rng = np.random.default_rng(7)
    a, b = rng.standard_normal(sa) * 1e3, rng.standard_normal(sb) * 1e-3
    np.testing.assert_array_equal(cross(a, b), np.cross(a, b))


def test_right_handed_unit_vectors():
    e = np.eye(3)
    np.testing.assert_array_equal(cross(e[0], e[1]), e[2])
    np.testing.assert_array_equal(cross(e[1], e[2]), e[0])
    np.testing.assert_array_equal(cross(e[2], e[0]), e[1])


@pytest.mark.parametrize("n", [1, 9, 2000])
def test_resultant_is_numpy_s_row_sums_bit_for_bit(n):
    """The force and moment sums of :func:`resultant` are ``sum(axis=0)`` of the rows and of
    their cross products (the reference), with most rows zero as on a contact surface; and a
    unit force at (0, 1, 0) along x has the moment (0, 0, -1)."""
    rng = np.random.default_rng(n)
    x, j = rng.normal(size=(n, 3)) * 4.0, rng.normal(size=(n, 3)) * 1e-3
    j[rng.random(n) < 0.8] = 0.0
    force, moment = resultant(x, j)
    assert np.array_equal(force, j.sum(axis=0))
    assert np.array_equal(moment, cross(x, j).sum(axis=0))
    f, m = resultant(np.array([[0.0, 1.0, 0.0]]), np.array([[1.0, 0.0, 0.0]]))
    assert f.tolist() == [1.0, 0.0, 0.0] and m.tolist() == [0.0, 0.0, -1.0]
