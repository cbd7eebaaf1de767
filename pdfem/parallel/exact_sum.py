"""Sums over particles that do not depend on how the particles are spread over ranks or threads.

A floating-point sum depends on the order of its terms, so a total taken as per-rank partial
sums added over the ranks (or per-thread chunks) changes in its last bits with the partition.
Here each process reduces its values to an exact expansion (Shewchuk 1997, "Adaptive
precision floating-point arithmetic and fast robust geometric predicates", Discrete Comput.
Geom. 18: the grow-expansion that Python's ``math.fsum`` uses): a few non-overlapping doubles
whose sum is exactly the sum of the values. The expansions of all ranks are gathered and
rounded once, as ``math.fsum`` rounds, so the result is the correctly rounded sum of all the
values: the same bits on 1 and N ranks, for any thread count and any order. Non-finite values
fall back to an ordinary sum (the result is then inf or nan either way). The kernels (integer
bins per exponent on the way into the expansions, the merge, the rounding) are in
:mod:`pdfem.parallel.exact_sum_kernels`.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numba
import numpy as np

from pdfem.parallel.exact_sum_kernels import (MAX_PARTIALS, NOT_FINITE, TOO_LONG, expansions,
                                              merge_expansions, round_groups,
                                              weighted_segment_expansions)

THREADED_FROM_TERMS = 65_536
"""Terms (rows x columns) from which the expansions are built on the threads: a term costs
2-3 ns in the bins (the level-ice sheet's regions, 10,800 terms: 34 us on one thread, 100 us
on two at a load of 2-3), a parallel region 10 us and more on a busy machine."""


def _chunks(rows: int, columns: int) -> tuple[bool, int]:
    """Whether a sum of ``columns`` columns over ``rows`` rows is threaded, and into how many
    chunks (each chunk's expansion is exact, so the rounded total does not depend on the
    count)."""
    parallel = rows * columns >= THREADED_FROM_TERMS and numba.get_num_threads() > 1
    return parallel, numba.get_num_threads() if parallel else 1


def fraction_expansion(values) -> list | None:
    """The exact sum of the finite doubles ``values`` as a few doubles whose sum it is exactly
    (rational arithmetic, slow: for a sum whose expansion outgrew :data:`MAX_PARTIALS`;
    each double takes the next 53 bits, so about 40 at most); None if that sum is beyond the
    doubles' range."""
    rest = sum(map(Fraction, values), Fraction(0))
    out = []
    try:
        while rest:
            x = float(rest)  # correctly rounded: what is left shrinks by 2^-53 or more
            out.append(x)
            rest -= Fraction(x)
    except OverflowError:
        return None
    return out[::-1]  # increasing magnitudes, as an expansion


def _one_process(out: np.ndarray, count: np.ndarray, comm) -> np.ndarray | None:
    """The totals of the groups' chunk expansions ``out`` ((G, C, M)) of lengths ``count``
    ((G, C)) when this is the only process and every term is finite (a numba pass, the same
    rounding as :func:`_rounded`); None otherwise (the general way)."""
    if comm.size != 1 or (count.size and count.min() < 0):
        return None
    totals = np.empty(out.shape[0])
    return totals if round_groups(out, count, totals) else None


def _merged(out: np.ndarray, count: np.ndarray, terms) -> tuple[np.ndarray, np.ndarray]:
    """This process's expansion of each group g from its chunks' ``out[g]`` ((G, C, M)) and
    lengths ``count[g]`` ((G, C)): ``(merged (G, M), lengths (G,))``; a group TOO_LONG is
    taken by :func:`fraction_expansion` of its terms (``terms(g)``), NOT_FINITE stays."""
    merged = np.empty((out.shape[0], MAX_PARTIALS))
    lengths = np.empty(out.shape[0], dtype=np.int64)
    merge_expansions(out, count, merged, lengths)
    for g in np.flatnonzero(lengths == TOO_LONG):
        e = fraction_expansion(terms(g).tolist())
        lengths[g] = NOT_FINITE if e is None else len(e)
        if e is not None:
            merged[g, :len(e)] = e
    return merged, lengths


def _rounded(merged: np.ndarray, lengths: np.ndarray, comm, terms) -> np.ndarray:
    """The correctly rounded totals over all ranks of each group's expansion (one gather;
    collective); a group NOT_FINITE on some rank takes the ordinary sum of its terms
    (``terms(g)``) over the ranks."""
    top = max(int(lengths.max(initial=0)), 0)
    parts = comm.allgather((merged[:, :top], lengths))
    groups, width = len(lengths), max(p.shape[1] for p, _ in parts)
    if len(parts) == 1 and width == top:
        stacked, counts = merged[:, None, :top], lengths[:, None]
    else:
        stacked = np.zeros((groups, len(parts), width))
        for q, (p, _) in enumerate(parts):
            stacked[:, q, :p.shape[1]] = p
        counts = np.stack([c for _, c in parts], axis=1)
    totals = np.empty(groups)
    if not round_groups(np.ascontiguousarray(stacked), np.ascontiguousarray(counts), totals):
        raise OverflowError("intermediate overflow in an exact sum")  # as math.fsum says it
    for g in np.flatnonzero((counts < 0).any(axis=1)):
        totals[g] = comm.allreduce_sum(float(np.sum(terms(g))))
    return totals


def exact_sums(arrays: list, comm, rows: np.ndarray | None = None) -> list:
    """:func:`exact_sum` of each array of ``arrays`` over ``rows`` (default every row), with one
    gather of the expansions for all of them (collective under MPI)."""
    idx = np.zeros(0, dtype=np.int64) if rows is None else np.asarray(rows, dtype=np.int64)
    parts = []
    for values in arrays:
        a = np.asarray(values, dtype=np.float64)
        a2 = np.ascontiguousarray(a[:, None] if a.ndim == 1 else
                                  a.reshape(a.shape[0], int(np.prod(a.shape[1:]))))
        parallel, chunks = _chunks(a2.shape[0] if rows is None else len(idx), a2.shape[1])
        out = np.empty((a2.shape[1], chunks, MAX_PARTIALS))
        count = np.empty((a2.shape[1], chunks), dtype=np.int64)
        expansions(parallel, a2, idx, rows is None, out, count)
        parts.append((a2, out, count))
    fast = [_one_process(out, count, comm) for _, out, count in parts]
    if all(t is not None for t in fast):
        totals = np.concatenate(fast) if fast else np.zeros(0)
    else:
        def column(a2, c):   # a column's terms, made only when a group needs them
            return a2[:, c] if rows is None else a2[idx, c]

        columns, merged, lengths = [], [], []
        for a2, out, count in parts:
            m, n = _merged(out, count, lambda c, a2=a2: column(a2, c))
            columns += [(a2, c) for c in range(a2.shape[1])]
            merged.append(m)
            lengths.append(n)
        totals = _rounded(np.concatenate(merged), np.concatenate(lengths), comm,
                          lambda g: column(*columns[g]))
    out, k = [], 0
    for values in arrays:
        shape = np.shape(values)[1:]
        size = int(np.prod(shape))
        out.append(float(totals[k]) if not shape else totals[k:k + size].reshape(shape))
        k += size
    return out


def exact_weighted_sums(w: np.ndarray, values: np.ndarray, segments: list, comm) -> np.ndarray:
    """Per segment of rows, the correctly rounded totals over all ranks of ``sum w_i`` and
    ``sum w_i values[i]``, the products rounded once: ``(S, 1 + k)``, column 0 the weights'
    sum (one kernel pass and one gather for all segments; collective under MPI).

    Parameters
    ----------
    w
        (n,) weights (e.g. particle volumes, m^3).
    values
        (n, k) values per row (e.g. force densities, N/m^3).
    segments
        S arrays of row indices (this process's rows of each segment).
    comm
        The communicator (``allgather``, ``allreduce_sum``).
    """
    w = np.ascontiguousarray(w, dtype=np.float64)
    values = np.ascontiguousarray(values, dtype=np.float64)
    ptr = np.zeros(len(segments) + 1, dtype=np.int64)
    ptr[1:] = np.cumsum([len(g) for g in segments])
    idx = (np.concatenate(segments).astype(np.int64, copy=False) if segments
           else np.zeros(0, dtype=np.int64))
    k = 1 + values.shape[1]
    parallel, chunks = _chunks(len(idx), k)
    out = np.empty((len(segments), chunks, k, MAX_PARTIALS))
    count = np.empty((len(segments), chunks, k), dtype=np.int64)
    weighted_segment_expansions(parallel, w, values, idx, ptr, out, count)
    S = len(segments)
    groups = np.ascontiguousarray(out.transpose(0, 2, 1, 3)).reshape(S * k, chunks,
                                                                       MAX_PARTIALS)
    counts = np.ascontiguousarray(count.transpose(0, 2, 1)).reshape(S * k, chunks)
    totals = _one_process(groups, counts, comm)
    if totals is not None:
        return totals.reshape(S, k)

    def products(g):  # group g = s k + col: its terms, numpy's rounded products
        s, col = divmod(int(g), k)
        rows = idx[ptr[s]:ptr[s + 1]]
        return w[rows] if col == 0 else w[rows] * values[rows, col - 1]

    merged, lengths = _merged(groups, counts, products)
    return _rounded(merged, lengths, comm, products).reshape(S, k)


def exact_sum(values: np.ndarray, comm, rows: np.ndarray | None = None):
    """The correctly rounded sum over all ranks of ``values`` ((n,) -> float, (n, k) -> (k,)
    array) over ``rows`` (default every row; collective under MPI)."""
    return exact_sums([values], comm, rows)[0]
