"""Sums over particles that do not depend on how the particles are spread over ranks or threads.

A floating-point sum depends on the order of its terms, so a total taken as per-rank partial
sums added over the ranks (or per-thread chunks) changes in its last bits with the partition.
Here each process reduces its values to an exact expansion (Shewchuk 1997, "Adaptive
precision floating-point arithmetic and fast robust geometric predicates", Discrete Comput.
Geom. 18: the grow-expansion that Python's ``math.fsum`` uses): a few non-overlapping doubles
whose sum is exactly the sum of the values. The expansions of all ranks are gathered and
rounded once (:func:`math.fsum`), so the result is the correctly rounded sum of all the values:
the same bits on 1 and N ranks, for any thread count and any order. Non-finite values fall
back to an ordinary sum (the result is then inf or nan either way).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import prange

from pdfem.parallel.kernels import twin

MAX_PARTIALS = 64
"""Room for the partials of one column: an expansion of finite doubles never needs more than
about 40 (the exponent range over the mantissa width)."""


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


@twin(fastmath=False)
def expansions(values, rows, every, out, count):
    """Exact expansions of the column sums of ``values`` (n, k) over ``rows`` (indices; all
    rows if ``every``), one per column and chunk of the rows (C chunks of about equal length,
    C = ``out.shape[1]``, threaded over the chunks), into ``out`` (k, C, MAX_PARTIALS); their
    lengths into ``count`` (k, C), -1 where a value of the chunk is not finite."""
    k = values.shape[1]
    n = values.shape[0] if every else rows.shape[0]
    chunks = out.shape[1]
    for c in prange(chunks):
        for col in range(k):
            m = 0
            for t in range(n * c // chunks, n * (c + 1) // chunks):
                x = values[t, col] if every else values[rows[t], col]
                if not np.isfinite(x):
                    m = -1
                    break
                m = grow(x, out[col, c], m)
            count[col, c] = m


@twin(fastmath=False)
def weighted_segment_expansions(w, values, idx, ptr, out, count):
    """Per segment s (rows ``idx[ptr[s]:ptr[s+1]]``) and chunk c of its rows (C chunks of about
    equal length, C = ``out.shape[1]``, threaded over segments and chunks), the exact
    expansions of ``sum w_i`` and of ``sum w_i values[i, col]`` (each product rounded once, as
    numpy's ``w[:, None] * values``) into ``out[s, c, 0]`` and ``out[s, c, 1 + col]``
    ((S, C, 1 + k, MAX_PARTIALS)), their lengths into ``count`` ((S, C, 1 + k); -1 where a
    term is not finite)."""
    k = values.shape[1]
    chunks = out.shape[1]
    for sc in prange((ptr.shape[0] - 1) * chunks):
        s, c = sc // chunks, sc % chunks
        n = ptr[s + 1] - ptr[s]
        for col in range(k + 1):
            partials = out[s, c, col]
            m = 0
            for t in range(ptr[s] + n * c // chunks, ptr[s] + n * (c + 1) // chunks):
                i = idx[t]
                x = w[i] if col == 0 else w[i] * values[i, col - 1]
                if not np.isfinite(x):
                    m = -1
                    break
                m = grow(x, partials, m)
            count[s, c, col] = m


THREADED_FROM_TERMS = 8_192
"""Terms (rows x columns) from which the expansions are built on the threads: a term costs
5-20 ns (more as the expansion grows), a parallel region about 10 us."""


def _chunks(rows: int, columns: int) -> tuple[bool, int]:
    """Whether a sum of ``columns`` columns over ``rows`` rows is threaded, and into how many
    chunks (each chunk's expansion is exact, so the rounded total does not depend on the
    count)."""
    parallel = rows * columns >= THREADED_FROM_TERMS and numba.get_num_threads() > 1
    return parallel, numba.get_num_threads() if parallel else 1


def local_expansion(values: np.ndarray, rows: np.ndarray | None = None) -> list:
    """This process's part of an exact sum: per column of ``values`` ((n,) or (n, k)) over
    ``rows`` (default all), its list of partials, or None where a value is not finite."""
    a = np.asarray(values, dtype=np.float64)
    a2 = a[:, None] if a.ndim == 1 else a.reshape(a.shape[0], int(np.prod(a.shape[1:])))
    idx = np.zeros(0, dtype=np.int64) if rows is None else np.asarray(rows, dtype=np.int64)
    parallel, chunks = _chunks(a2.shape[0] if rows is None else len(idx), a2.shape[1])
    out = np.empty((a2.shape[1], chunks, MAX_PARTIALS))
    count = np.empty((a2.shape[1], chunks), dtype=np.int64)
    expansions(parallel, np.ascontiguousarray(a2), idx, rows is None, out, count)
    return [None if (c < 0).any() else [x for q in range(chunks) for x in out[col, q, :c[q]].tolist()]
            for col, c in enumerate(count)]


def round_expansions(parts: list[list], plain: np.ndarray | float) -> np.ndarray:
    """The correctly rounded totals of the per-process expansions ``parts`` (one list per
    process, one entry per column); a column with a non-finite value anywhere takes ``plain``
    (an ordinary sum of the same values)."""
    plain = np.atleast_1d(np.asarray(plain, dtype=np.float64))
    out = np.empty(len(parts[0]))
    for col in range(len(out)):
        cols = [p[col] for p in parts]
        out[col] = plain[col] if any(c is None for c in cols) else math.fsum(
            x for c in cols for x in c)
    return out


def exact_sums(arrays: list, comm, rows: np.ndarray | None = None) -> list:
    """:func:`exact_sum` of each array of ``arrays`` over ``rows`` (default every row), with one
    gather of the expansions for all of them (collective under MPI)."""
    parts = comm.allgather([local_expansion(values, rows) for values in arrays])
    out = []
    for k, values in enumerate(arrays):
        mine = [p[k] for p in parts]
        if any(c is None for p in mine for c in p):
            a = np.asarray(values, dtype=np.float64)
            a = a if rows is None else a[np.asarray(rows, dtype=np.int64)]
            plain = comm.allreduce_sum(a.sum(axis=0))
        else:
            plain = 0.0
        total = round_expansions(mine, plain)
        out.append(float(total[0]) if np.ndim(values) == 1
                   else total.reshape(np.shape(values)[1:]))
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
    used = out[:, :, :, :max(int(count.max(initial=0)), 0)].tolist()
    mine = [[None if any(counts[q][col] < 0 for q in range(chunks))
             else [x for q in range(chunks) for x in rows[q][col][:counts[q][col]]]
             for col in range(k)] for rows, counts in zip(used, count.tolist())]
    parts = comm.allgather(mine)
    total = np.empty((len(segments), k))
    for s in range(len(segments)):
        for col in range(k):
            terms = [p[s][col] for p in parts]
            if any(t is None for t in terms):  # not finite somewhere: a plain sum
                rows = idx[ptr[s]:ptr[s + 1]]
                x = w[rows] if col == 0 else w[rows] * values[rows, col - 1]
                total[s, col] = comm.allreduce_sum(float(x.sum()))
            else:
                total[s, col] = math.fsum([x for t in terms for x in t])
    return total


def exact_sum(values: np.ndarray, comm, rows: np.ndarray | None = None):
    """The correctly rounded sum over all ranks of ``values`` ((n,) -> float, (n, k) -> (k,)
    array) over ``rows`` (default every row; collective under MPI)."""
    return exact_sums([values], comm, rows)[0]
