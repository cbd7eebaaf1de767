"""Correctly rounded sums over particles (:mod:`pdfem.parallel.exact_sum`).

Reference: Python's ``math.fsum`` (Shewchuk's exact summation, correctly rounded) of the same
values; sums that cancel catastrophically and columns that are mostly zeros (the block matrices
of the regions' reactions) included.
"""

from __future__ import annotations

import math

import numpy as np

from pdfem.parallel.comm import SerialComm
from pdfem.parallel.exact_sum import exact_sum, exact_sums, exact_weighted_sums


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


class _TwoRanks(SerialComm):
    """A serial communicator that reports this process's part twice, as two ranks holding the
    same rows would (the gathered expansions of both are rounded once)."""

    size = 2

    def allgather(self, obj):
        return [obj, obj]

    def allreduce_sum(self, value):
        return value + value


def test_weighted_segment_sums_are_the_correctly_rounded_sums_of_the_rounded_products():
    rng = np.random.default_rng(12)
    w = rng.uniform(1e-7, 2e-6, 900)                     # particle volumes, m^3
    f = rng.normal(size=(900, 3)) * 1e9                  # force densities, N/m^3
    f[100:200] = -f[:100]                                # cancelling rows
    segments = [rng.permutation(900)[:160], np.arange(300, 600), np.zeros(0, dtype=np.int64)]
    got = exact_weighted_sums(w, f, segments, SerialComm())
    assert got.shape == (3, 4)
    for s, rows in enumerate(segments):
        prod = w[rows, None] * f[rows]                   # numpy's rounded products
        assert got[s, 0] == math.fsum(w[rows])
        assert got[s, 1:].tolist() == [math.fsum(prod[:, c]) for c in range(3)]
    doubled = exact_weighted_sums(w, f, segments, _TwoRanks())
    for s, rows in enumerate(segments):
        prod = w[rows, None] * f[rows]
        assert doubled[s, 1:].tolist() == [math.fsum(np.concatenate([prod[:, c]] * 2))
                                           for c in range(3)]


def test_weighted_segment_sums_with_a_non_finite_value_fall_back_to_a_plain_sum():
    w = np.ones(4)
    f = np.array([[1.0, 0.0, 0.0], [np.nan, 0.0, 0.0], [2.0, 1.0, 0.0], [3.0, 0.0, 0.0]])
    got = exact_weighted_sums(w, f, [np.array([0, 1, 2]), np.array([2, 3])], SerialComm())
    assert math.isnan(got[0, 1]) and got[0, 2] == 1.0 and got[0, 0] == 3.0
    assert got[1].tolist() == [2.0, 5.0, 1.0, 0.0]


def test_threaded_chunks_give_the_same_correctly_rounded_sums():
    """From THREADED_FROM_TERMS terms the expansions are built per chunk on the threads; each
    chunk's is exact, so the totals are still math.fsum's (and a non-finite value in one
    chunk still falls back to a plain sum)."""
    from pdfem.parallel.exact_sum import THREADED_FROM_TERMS
    rng = np.random.default_rng(21)
    n = 2 * THREADED_FROM_TERMS + 7
    big = rng.normal(size=(n // 2, 3)) * 1e15
    values = np.concatenate([big, -big[::-1], rng.normal(size=(n - 2 * (n // 2), 3))])
    values[::5] += rng.normal(size=(len(values[::5]), 3))
    assert exact_sum(values, SerialComm()).tolist() == [math.fsum(values[:, c]) for c in range(3)]
    w = rng.uniform(1e-7, 2e-6, n)
    segments = [np.arange(n), rng.permutation(n)[:THREADED_FROM_TERMS // 4 + 3]]
    got = exact_weighted_sums(w, values, segments, SerialComm())
    for s, rows in enumerate(segments):
        prod = w[rows, None] * values[rows]
        assert got[s, 0] == math.fsum(w[rows])
        assert got[s, 1:].tolist() == [math.fsum(prod[:, c]) for c in range(3)]
    values[n - 3, 2] = np.inf
    assert math.isinf(exact_sum(values, SerialComm())[2])


def test_terms_over_the_whole_exponent_range_in_the_bins_and_beyond(monkeypatch):
    """The integer bins per exponent take any finite double exactly: thousands of terms (many
    bin flushes) from subnormals to 1e300, mixed signs, the largest doubles (past the bins,
    grown directly), and a spread so wide that a chunk's expansion outgrows its room (then
    taken by exact rational arithmetic): every sum is math.fsum's, bit for bit, threaded or
    not, plain and weighted."""
    from pdfem.parallel.exact_sum_kernels import FLUSH_EVERY, MAX_PARTIALS, TOO_LONG, expansions

    rng = np.random.default_rng(30)
    n = 5 * FLUSH_EVERY + 3
    cases = {
        "subnormal": rng.normal(size=n) * 5e-324 * rng.integers(1, 2 ** 52, n),
        "decades": rng.normal(size=n) * 10.0 ** rng.integers(-300, 300, n),
        "largest": rng.choice([-1.0, 1.0], n) * 2.0 ** rng.integers(1013, 1020, n) / 64,
        "one": rng.choice([-1.0, 1.0], n) * (1.0 - 2.0 ** -53),
    }
    import pdfem.parallel.exact_sum as exact_sum_module

    for name, v in cases.items():
        for threads in (False, True):
            # threaded (in chunks, one per thread) from this many terms: every sum here or none
            monkeypatch.setattr(exact_sum_module, "THREADED_FROM_TERMS", 1 if threads else 10 ** 9)
            rows = np.arange(0, n, 1 if threads else 2)
            assert exact_sum(v, SerialComm(), rows) == math.fsum(v[rows]), name
        w = rng.uniform(0.5, 2.0, n)
        got = exact_weighted_sums(w, np.stack([v, -v], axis=1), [np.arange(n)], SerialComm())
        assert got[0].tolist() == [math.fsum(w), math.fsum(w * v), math.fsum(w * -v)], name
    # the decades spread outgrows MAX_PARTIALS in one chunk: the kernel says so, the sum holds
    out = np.empty((1, 1, MAX_PARTIALS))
    count = np.empty((1, 1), dtype=np.int64)
    expansions(False, cases["decades"][:, None], np.zeros(0, dtype=np.int64), True, out, count)
    assert count[0, 0] == TOO_LONG
