"""The numba kernels of the exact sums (:mod:`pdfem.parallel.exact_sum`): integer bins per
binary exponent, Shewchuk's expansions, their merge and their correct rounding.

The terms reach an expansion through integer bins, one per binary exponent (a
"superaccumulator" in the manner of Neal 2015, "Fast exact summation using small and large
superaccumulators", arXiv:1505.05571): a double is ``+-M 2^(e - 1075)`` with an integer
``M < 2^53`` and its biased exponent ``e`` (1 for subnormals), so adding ``+-M`` to the int64
bin of ``e`` is exact. Every :data:`FLUSH_EVERY` terms (before a bin can overflow) each used
bin goes into the expansion (Shewchuk 1997, "Adaptive precision floating-point arithmetic and
fast robust geometric predicates", Discrete Comput. Geom. 18: the grow-expansion that
Python's ``math.fsum`` uses) as two doubles, exactly. A term costs a few integer operations
instead of a pass over the expansion (growing the expansion term by term cost 10-60 ns a term
once it held several partials). The expansions of the chunks and of the ranks are merged by
the same grow-expansion and rounded once by the last step of CPython's ``math.fsum``
(Modules/mathmodule.c, ``math_fsum``: the partials summed from the top until the sum becomes
inexact, with its half-even correction), so the result is the correctly rounded sum of all
the terms: the same bits as ``math.fsum`` of them in any order.

Lengths: an expansion's length, or :data:`NOT_FINITE` where a term is not finite, or
:data:`TOO_LONG` where it outgrew :data:`MAX_PARTIALS` (only terms spread over hundreds of
binary orders do that; :mod:`pdfem.parallel.exact_sum` then takes that sum by exact rational
arithmetic).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import prange

from pdfem.parallel.kernels import float_bits, twin

NOT_FINITE, TOO_LONG = -1, -2
"""The lengths of an expansion with a non-finite term, and of one that outgrew its room."""

MAX_PARTIALS = 64
"""Room for the partials of one column. The partials of an expansion do not overlap, but its
length is not bounded by the exponent range over the mantissa width: terms spread over
hundreds of decades can outgrow the room, and the expansion is then TOO_LONG (taken by exact
rationals, :mod:`pdfem.parallel.exact_sum`)."""

BIN_NOT_FINITE, BIN_ABOVE = -1, -2
""":func:`to_bin`'s answers for a term that is not finite and for one above :data:`TOP_BIN`
(added to the expansion directly)."""

BINS = 2048
"""One integer bin per biased exponent of a double (0-2047)."""

FLUSH_EVERY = 512
"""Terms added to the bins before they go into the expansion: each adds less than 2^53 to a
bin, so a bin stays below 2^62 (and its split into two doubles exact)."""

TOP_BIN = 2036
"""Exponents from here on (|x| >= 2^1013) skip the bins and grow the expansion directly: a bin
of up to 2^62 there would overflow a double when split."""


@numba.njit(cache=True, inline="always")
def grow(x, partials, m):
    """Add the finite value ``x`` to the expansion ``partials[:m]`` (Shewchuk's grow-expansion,
    as :func:`math.fsum`); returns its new length."""
    if x == 0.0:  # adds nothing to the exact sum
        return m
    i = 0
    for q in range(m):
        y = partials[q]
        if abs(x) < abs(y):
            x, y = y, x
        hi = x + y
        lo = y - (hi - x)
        if lo != 0.0:
            partials[i] = lo
            i += 1
        x = hi
    partials[i] = x
    return i + 1


@numba.njit(cache=True, inline="always")
def to_bin(x, bins):
    """Add the double ``x`` to its exponent's bin of ``bins`` (BINS,) int64, exactly; returns
    the bin (0: ``x`` is zero and added nothing), :data:`BIN_NOT_FINITE` if ``x`` is not
    finite, :data:`BIN_ABOVE` if it is too large for the bins (:data:`TOP_BIN`: the caller
    grows the expansion with it)."""
    b = float_bits(x)
    e = (b >> 52) & 0x7FF
    if e == 0x7FF:
        return BIN_NOT_FINITE
    if e >= TOP_BIN:
        return BIN_ABOVE
    mant = b & 0xFFFFFFFFFFFFF
    if e == 0:  # subnormal (or zero): the same scale as e = 1, no implicit bit
        if mant == 0:
            return 0
        e = 1
    else:
        mant |= 0x10000000000000
    bins[e] += -mant if b < 0 else mant
    return e


@numba.njit(cache=True, inline="always")
def grow_room(x, partials, m):
    """:func:`grow` where ``partials`` has room for one more partial; else TOO_LONG."""
    if m < 0 or m >= partials.shape[0]:
        return TOO_LONG
    return grow(x, partials, m)


@numba.njit(cache=True)
def flush_bins(bins, lo, hi, partials, m):
    """Grow the expansion ``partials[:m]`` by the bins ``lo..hi`` (each bin a = high + low,
    both exact doubles once scaled by 2^(e - 1075)) and empty them; returns its new length, or
    TOO_LONG when it would outgrow ``partials``."""
    for e in range(lo, hi + 1):
        a = bins[e]
        if a != 0:
            bins[e] = 0
            low = a & 0xFFFFFFFF
            m = grow_room(math.ldexp(float(a - low), e - 1075), partials, m)
            m = grow_room(math.ldexp(float(low), e - 1075), partials, m)
    return m


@numba.njit(cache=True, inline="always")
def column_expansion(values, rows, every, w, weighted, col, t0, t1, bins, partials):
    """The exact expansion of one column's terms t0..t1 into ``partials``; returns its length
    (or NOT_FINITE / TOO_LONG). Term t is ``values[i, col]`` with ``i = t`` (``every``) or
    ``rows[t]``; ``weighted``: ``w[i]`` for column 0, else ``w[i] values[i, col - 1]``.
    ``bins`` (BINS,) are empty before and after."""
    m, lo, hi, added = 0, BINS, 0, 0
    for t in range(t0, t1):
        i = t if every else rows[t]
        if weighted:
            x = w[i] if col == 0 else w[i] * values[i, col - 1]
        else:
            x = values[i, col]
        e = to_bin(x, bins)
        if e > 0:
            lo = min(lo, e)
            hi = max(hi, e)
            added += 1
            if added == FLUSH_EVERY:
                m = flush_bins(bins, lo, hi, partials, m)
                lo, hi, added = BINS, 0, 0
        elif e == BIN_ABOVE:
            m = grow_room(x, partials, m)
        elif e == BIN_NOT_FINITE:  # not finite: empty the bins and stop
            for b in range(lo, hi + 1):
                bins[b] = 0
            return NOT_FINITE
    return flush_bins(bins, lo, hi, partials, m)


@twin(fastmath=False)
def expansions(values, rows, every, out, count):
    """Exact expansions of the column sums of ``values`` (n, k) over ``rows`` (indices; all
    rows if ``every``), one per column and chunk of the rows (C chunks of about equal length,
    C = ``out.shape[1]``, threaded over the chunks), into ``out`` (k, C, MAX_PARTIALS); their
    lengths into ``count`` (k, C)."""
    k = values.shape[1]
    n = values.shape[0] if every else rows.shape[0]
    chunks = out.shape[1]
    no_w = np.empty(0)
    for c in prange(chunks):
        bins = np.zeros(BINS, dtype=np.int64)
        for col in range(k):
            partials = out[col, c]
            count[col, c] = column_expansion(values, rows, every, no_w, False, col,
                                             n * c // chunks, n * (c + 1) // chunks, bins,
                                             partials)


@twin(fastmath=False)
def weighted_segment_expansions(w, values, idx, ptr, out, count):
    """Per segment s (rows ``idx[ptr[s]:ptr[s+1]]``) and chunk c of its rows (C chunks of about
    equal length, C = ``out.shape[1]``, threaded over segments and chunks), the exact
    expansions of ``sum w_i`` and of ``sum w_i values[i, col]`` (each product rounded once, as
    numpy's ``w[:, None] * values``) into ``out[s, c, 0]`` and ``out[s, c, 1 + col]``
    ((S, C, 1 + k, MAX_PARTIALS)), their lengths into ``count`` ((S, C, 1 + k))."""
    k = values.shape[1]
    chunks = out.shape[1]
    for sc in prange((ptr.shape[0] - 1) * chunks):
        s, c = sc // chunks, sc % chunks
        n = ptr[s + 1] - ptr[s]
        bins = np.zeros(BINS, dtype=np.int64)
        for col in range(k + 1):
            partials = out[s, c, col]
            count[s, c, col] = column_expansion(values, idx, False, w, True, col,
                                                ptr[s] + n * c // chunks,
                                                ptr[s] + n * (c + 1) // chunks, bins, partials)


@numba.njit(cache=True)
def merge_expansions(parts, counts, merged, lengths):
    """Per group g, the expansions ``parts[g, q, :counts[g, q]]`` of its pieces q (chunks or
    ranks) grown into one, ``merged[g, :lengths[g]]``; a group with a piece NOT_FINITE is
    NOT_FINITE, one with a piece or a merge TOO_LONG is TOO_LONG."""
    for g in range(parts.shape[0]):
        m = 0
        for q in range(parts.shape[1]):
            c = counts[g, q]
            if c < 0:
                m = NOT_FINITE if c == NOT_FINITE or m == NOT_FINITE else TOO_LONG
                if m == NOT_FINITE:
                    break
            for t in range(max(c, 0)):
                if m >= 0:
                    m = grow_room(parts[g, q, t], merged[g], m)
        lengths[g] = m


@numba.njit(cache=True, inline="always")
def round_expansion(partials, m):
    """The correctly rounded value of the expansion ``partials[:m]`` (increasing magnitudes,
    non-overlapping, as :func:`grow` leaves it): the last step of CPython's ``math.fsum``."""
    if m == 0:
        return 0.0
    n = m - 1
    hi = partials[n]
    lo = 0.0
    while n > 0:
        x = hi
        n -= 1
        y = partials[n]
        hi = x + y
        yr = hi - x
        lo = y - yr
        if lo != 0.0:
            break
    # half-even rounding across several partials (CPython's comment: sum([1e-16, 1, 1e16])
    # rounds the last digit up, the 1e-16 making the 1 slightly closer to two)
    if n > 0 and ((lo < 0.0 and partials[n - 1] < 0.0) or (lo > 0.0 and partials[n - 1] > 0.0)):
        y = lo * 2.0
        x = hi + y
        yr = x - hi
        if y == yr:
            hi = x
    return hi


@numba.njit(cache=True)
def round_groups(parts, counts, totals):
    """Per group g with every piece's length ``counts[g, q]`` >= 0, the correctly rounded sum
    of its pieces' expansions ``parts[g, q, :counts[g, q]]`` into ``totals[g]`` (the others
    are left as they were); returns whether every such total is finite (a sum near the
    largest double can overflow in the merge)."""
    scratch = np.empty(parts.shape[1] * parts.shape[2] + 1)
    finite = True
    for g in range(parts.shape[0]):
        ok = True
        for q in range(parts.shape[1]):
            if counts[g, q] < 0:
                ok = False
        if not ok:
            continue
        m = 0
        for q in range(parts.shape[1]):
            for t in range(counts[g, q]):
                m = grow(parts[g, q, t], scratch, m)
        totals[g] = round_expansion(scratch, m)
        if not math.isfinite(totals[g]):
            finite = False
    return finite

