"""Machinery of the chunked pair loops: overflow adds and the layout's checks.

The pair loops (:mod:`pdfem.pd.bonds.pair_step_kernels`, :mod:`pdfem.pd.bonds.pair_sum_kernels`) cut the
particles into chunks of equal pair count (:class:`pdfem.pd.bonds.workspace.PairWorkspace` holds the
layout); each chunk writes the j side of a bond that leaves the chunk into its overflow buffer,
and :func:`add_overflow1` / :func:`add_overflow3` add those buffers in fixed chunk order.
:func:`pairs_forward` and :func:`chunk_split` check and analyse a pair list for the layout.

The kernels are built by :mod:`pdfem.parallel.kernels` (:func:`twin`, :data:`FASTMATH`,
:func:`fma`: same input, same output whatever the state of numba's on-disk cache).
"""

from __future__ import annotations

import numba
import numpy as np

U64 = np.uint64


@numba.njit(cache=True)
def add_overflow1(t, cb, ov_ptr, ov, col, out):
    """Add the overflow of chunks 0..t-1 (in that order) into the rows of chunk t."""
    r0 = cb[t]
    r1 = cb[t + 1]
    for c in range(t):
        s = cb[c + 1]
        base = ov_ptr[c]
        e = s + (ov_ptr[c + 1] - base)
        lo = max(s, r0)
        hi = min(e, r1)
        for p in range(lo, hi):
            out[p] += ov[base + p - s, col]


@numba.njit(cache=True)
def add_overflow3(t, cb, ov_ptr, ov, out):
    """:func:`add_overflow1` for (N, 3) outputs (all three columns)."""
    for col in range(3):
        add_overflow1(t, cb, ov_ptr, ov, col, out[:, col])


@numba.njit(cache=True)
def pairs_forward(row_ptr, nbr):
    """True when every pair of row i has i < nbr[k] < N (what the chunked loops rely on)."""
    n = row_ptr.shape[0] - 1
    for i in range(n):
        if row_ptr[i + 1] < row_ptr[i]:
            return False
        for k in range(row_ptr[i], row_ptr[i + 1]):
            j = nbr[k]
            if j <= i or j >= n:
                return False
    return True


@numba.njit(cache=True)
def chunk_split(row_ptr, nbr, cb):
    """Per chunk, the first row with a partner beyond the chunk (rows before it need no check)."""
    C = cb.shape[0] - 1
    split = cb[1:].copy()
    for c in range(C):
        for i in range(cb[c], cb[c + 1]):
            hit = False
            for k in range(row_ptr[i], row_ptr[i + 1]):
                if nbr[k] >= cb[c + 1]:
                    hit = True
                    break
            if hit:
                split[c] = i
                break
    return split


@numba.njit(cache=True)
def max_reach(row_ptr, nbr, gid):
    """The largest gid[j] - gid[i] over the bonds (i, j) (0 without bonds)."""
    out = 0
    for i in range(row_ptr.shape[0] - 1):
        for k in range(row_ptr[i], row_ptr[i + 1]):
            out = max(out, gid[nbr[k]] - gid[i])
    return out
