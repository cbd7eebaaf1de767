"""Triangular solves with the ``L D L^T`` factors of symmetric sparse blocks (numba).

A symmetric matrix factorised by SuperLU with the same permutation of rows and columns and no
pivoting (``diag_pivot_thresh = 0``, the diagonal always taken: sound for a positive definite
matrix, Golub & Van Loan, *Matrix Computations*, 4th ed., Sec. 4.2) has ``U = D L^T`` with
``D = diag(U)``. Keeping only ``L`` (strictly lower part, compressed columns, 32-bit row indices)
and ``D`` halves the bytes a solve reads against SuperLU's ``L`` and ``U``: the four blades of the
milling propeller (10-node tetrahedra of 0.1 m, 14,031 free DOFs) hold 17 MB instead of 34 MB,
which fits the last-level cache of a common processor (32 MB here), and a solve is three passes:

    L y = P b  (by columns),   z = y / d,   L^T w = z  (by the columns of L, as rows of L^T),
    x = P^T w.

The blocks are independent (:mod:`pdfem.fem.block_factor`) and are solved in parallel, one block
per thread, each in the same order of operations whatever the thread: the same bits on any
number of threads. Every array is flat; block ``b`` owns ``order[dof_ptr[b]:dof_ptr[b + 1]]``
(the DOF at each factor position) and the ``n_b + 1`` column pointers from ``col_at[b]`` on in
``col_ptr``, whose values index the concatenated ``rows`` and ``vals``.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from pdfem.parallel.kernels import twin


@twin(fastmath=False)
def solve_blocks(blocks, dof_ptr, order, col_at, col_ptr, rows, vals, diag, b, x):
    """``x[order of block k] = A_k^-1 b[...]`` for each block ``k`` in ``blocks``, for every
    column of ``b`` and ``x`` (shape (n, m)); a column whose right-hand side is zero on a block
    gets zeros there (exactly the solution)."""
    for q in prange(blocks.shape[0]):
        k = blocks[q]
        lo = dof_ptr[k]
        n = dof_ptr[k + 1] - lo
        cp = col_at[k]
        y = np.empty(n)
        for c in range(b.shape[1]):
            nonzero = False
            for j in range(n):
                y[j] = b[order[lo + j], c]
                if y[j] != 0.0:
                    nonzero = True
            if not nonzero:
                for j in range(n):
                    x[order[lo + j], c] = 0.0
                continue
            for j in range(n):                       # L y = P b, unit lower, by columns
                yj = y[j]
                if yj != 0.0:
                    for p in range(col_ptr[cp + j], col_ptr[cp + j + 1]):
                        y[rows[p]] -= vals[p] * yj
            for j in range(n):
                y[j] = y[j] / diag[lo + j]
            for j in range(n - 1, -1, -1):           # L^T w = z: row j of L^T is column j of L
                s = y[j]
                for p in range(col_ptr[cp + j], col_ptr[cp + j + 1]):
                    s -= vals[p] * y[rows[p]]
                y[j] = s
            for j in range(n):
                x[order[lo + j], c] = y[j]
