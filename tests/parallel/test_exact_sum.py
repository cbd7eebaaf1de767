"""Correctly rounded sums over particles (:mod:`pdfem.parallel.exact_sum`).

Reference: Python's ``math.fsum`` (Shewchuk's exact summation, correctly rounded) of the same
values; sums that cancel catastrophically and columns that are mostly zeros (the block matrices
of the regions' reactions) included.
"""

from __future__ import annotations

import math

import numpy as np

from pdfem.parallel.comm import SerialComm
from pdfem.parallel.exact_sum import exact_sum, exact_sums


def test_columns_are_the_correctly_rounded_sums_in_any_order():
    rng = np.random.default_rng(4)
    big = rng.normal(size=(500, 3)) * 1e16
    values = np.concatenate([big, -big, rng.normal(size=(500, 3)), np.zeros((300, 3))])
    values[::7, 1] = 0.0
    expected = [math.fsum(values[:, c]) for c in range(3)]
    got = exact_sum(values, SerialComm())
    assert got.tolist() == expected
    shuffled = values[rng.permutation(len(values))]
    assert exact_sum(shuffled, SerialComm()).tolist() == expected
    rows = np.arange(0, len(values), 3)
    assert exact_sum(values, SerialComm(), rows).tolist() == [math.fsum(values[rows, c])
                                                              for c in range(3)]


def test_zeros_and_non_finite_values():
    assert exact_sum(np.zeros(10), SerialComm()) == 0.0
    assert exact_sum(np.zeros((0, 4)), SerialComm()).tolist() == [0.0] * 4
    assert math.isinf(exact_sum(np.array([1.0, np.inf, 0.0]), SerialComm()))


def test_several_arrays_in_one_collective_give_each_array_s_sum():
    rng = np.random.default_rng(8)
    arrays = [rng.normal(size=40), rng.normal(size=(7, 3)) * 1e8, np.zeros((0, 3))]
    got = exact_sums(arrays, SerialComm())
    assert got[0] == math.fsum(arrays[0])
    assert got[1].tolist() == [math.fsum(arrays[1][:, c]) for c in range(3)]
    assert got[2].tolist() == [0.0, 0.0, 0.0]
