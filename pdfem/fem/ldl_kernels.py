"""Triangular solves with the ``L D L^T`` factors of symmetric sparse blocks (numba).

A symmetric matrix factorised by SuperLU with the same permutation of rows and columns and no
pivoting (``diag_pivot_thresh = 0``, the diagonal always taken: sound for a positive definite
matrix, Golub & Van Loan, *Matrix Computations*, 4th ed., Sec. 4.2) has ``U = D L^T`` with
``D = diag(U)``. Keeping only ``L`` (strictly lower part, compressed columns, block-local row
indices of 16 or 32 bits, :data:`pdfem.fem.block_factor.ROWS_16_BITS`) and ``D`` halves the
bytes a solve reads against SuperLU's ``L`` and ``U``: the four blades of the milling propeller
(10-node tetrahedra of 0.1 m, 14,031 free DOFs) hold 17 MB with 32-bit row indices (14 MB with
16-bit ones) instead of 34 MB, which fits the last-level cache of a common processor (32 MB
here), and a solve is three passes:

    L y = P b  (by columns),   z = y / d,   L^T w = z  (by the columns of L, as rows of L^T),
    x = P^T w.

The blocks are independent (:mod:`pdfem.fem.block_factor`) and are solved in parallel, one block
per thread, each in the same order of operations whatever the thread: the same bits on any
number of threads. Every array is flat; block ``b`` owns ``order[dof_ptr[b]:dof_ptr[b + 1]]``
(the DOF at each factor position) and the ``n_b + 1`` column pointers from ``col_at[b]`` on in
``col_ptr``, whose values index the concatenated ``rows`` and ``vals``.

The forward pass skips a column whose entry is zero (it would subtract zeros): a right-hand
side that is zero but at a few DOFs (a contact impulse on a blade, a probe of the compliance)
touches only the columns it reaches in ``L``'s elimination tree, the backward pass every
column. The results are the bits of the full pass (the skipped updates add exact zeros; an
entry never reached stays +0).
"""

from __future__ import annotations

import numba
import numpy as np
from numba import prange

from pdfem.parallel.kernels import twin


@numba.njit(cache=True)
def _one(rows, vals, col_ptr, cp, diag, lo, y):
    """``y <- A^-1 y`` for one right-hand side in factor order: ``L``, ``D``, ``L^T``."""
    n = y.shape[0]
    for j in range(n):                               # L y = P b, unit lower, by columns
        yj = y[j]
        if yj == 0.0:                                # nothing to subtract (a sparse b)
            continue
        for p in range(col_ptr[cp + j], col_ptr[cp + j + 1]):
            y[rows[p]] -= vals[p] * yj
    for j in range(n):
        y[j] = y[j] / diag[lo + j]
    for j in range(n - 1, -1, -1):                   # L^T w = z: row j of L^T is column j of L
        s = y[j]
        for p in range(col_ptr[cp + j], col_ptr[cp + j + 1]):
            s -= vals[p] * y[rows[p]]
        y[j] = s


@numba.njit(cache=True)
def _many(rows, vals, col_ptr, cp, diag, lo, y):
    """``y <- A^-1 y`` for the columns of ``y`` (n, m) together, each entry of ``L`` read
    once for all, each column by the operations of :func:`_one`."""
    n, m = y.shape
    for j in range(n):
        zero = True
        for c in range(m):
            if y[j, c] != 0.0:
                zero = False
        if zero:                                     # nothing to subtract (sparse b)
            continue
        for p in range(col_ptr[cp + j], col_ptr[cp + j + 1]):
            r = rows[p]
            v = vals[p]
            for c in range(m):
                y[r, c] -= v * y[j, c]
    for j in range(n):
        d = diag[lo + j]
        for c in range(m):
            y[j, c] = y[j, c] / d
    s = np.empty(m)
    for j in range(n - 1, -1, -1):
        for c in range(m):
            s[c] = y[j, c]
        for p in range(col_ptr[cp + j], col_ptr[cp + j + 1]):
            r = rows[p]
            v = vals[p]
            for c in range(m):
                s[c] -= v * y[r, c]
        for c in range(m):
            y[j, c] = s[c]


@twin(fastmath=False)
def solve_blocks(blocks, dof_ptr, order, col_at, col_ptr, rows, vals, diag, b, x):
    """``x[c, order of block k] = A_k^-1 b[c, ...]`` for each block ``k`` in ``blocks`` and each
    right-hand side ``c`` (the rows of ``b`` and ``x``, shape (m, n)); several right-hand
    sides go through a block's factor together (:func:`_many`), each by the operations it
    would get alone (:func:`_one`). A block whose right-hand sides are all zero gets zeros
    (exactly the solution)."""
    m = b.shape[0]
    for q in prange(blocks.shape[0]):
        k = blocks[q]
        lo = dof_ptr[k]
        n = dof_ptr[k + 1] - lo
        nonzero = False
        for c in range(m):
            for j in range(n):
                if b[c, order[lo + j]] != 0.0:
                    nonzero = True
        if m == 1:
            y = np.empty(n)
            for j in range(n):
                y[j] = b[0, order[lo + j]]
            if nonzero:
                _one(rows, vals, col_ptr, col_at[k], diag, lo, y)
            for j in range(n):
                x[0, order[lo + j]] = y[j]
        else:
            z = np.empty((n, m))
            for j in range(n):
                for c in range(m):
                    z[j, c] = b[c, order[lo + j]]
            if nonzero:
                _many(rows, vals, col_ptr, col_at[k], diag, lo, z)
            for j in range(n):
                for c in range(m):
                    x[c, order[lo + j]] = z[j, c]
