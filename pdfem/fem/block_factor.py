"""A sparse symmetric matrix factorised block by block: its independent parts, solved on one
rank or split over the ranks.

The matrix of an implicit step, ``A = M + dt/2 C + dt^2/4 K`` on the free DOFs
(:mod:`pdfem.fem.implicit`), falls into independent blocks when the structure's parts meet only
through held DOFs: a propeller's blades clamped to its rigid hub, two panels on a rigid frame.
The blocks are the connected components of the matrix's graph (numbered by their smallest DOF).
Each is factorised alone (SuperLU, minimum-degree ordering of ``A + A^T``, symmetric mode, no
pivoting) and kept as ``L D L^T`` (:mod:`pdfem.fem.ldl_kernels`): half the bytes of SuperLU's
``L`` and ``U``, solved by a numba pass with one block per thread. The 4-blade propeller's 14,031
free DOFs (10-node tetrahedra of 0.1 m): 17 MB of factors with 32-bit row indices, 14 MB
with the 16 bits kept for blocks of up to 65,536 DOFs.

With a communicator of several ranks the blocks are dealt out by their non-zeros
(:class:`pdfem.parallel.deal.Dealt`), each rank factorises and solves only its own, and the
parts are shared with an all-gather. Every rank
then holds the same solution, bit for bit the one a single rank gets: each block is solved by
the same factorisation of the same matrix wherever it is, in the same order of operations on
any thread. A matrix of one block is solved on every rank (dealing it out would only add the
message). A block whose right-hand side is zero is not solved: its solution is exactly zero (a
contact impulse on one blade amends only that blade's step).
"""

from __future__ import annotations

import numba
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.sparse.csgraph import connected_components

from pdfem.fem.ldl_kernels import solve_blocks
from pdfem.geometry.cell_hash import members
from pdfem.parallel.comm import SerialComm
from pdfem.parallel.deal import Dealt

ROWS_16_BITS = 65_536
"""Largest block (DOFs) whose factor's row indices are kept in 16 bits (unsigned)."""


def independent_blocks(a: sp.spmatrix) -> list[np.ndarray]:
    """The DOFs (ascending) of each connected component of the graph of ``a`` (square), in the
    order of their smallest DOF."""
    n_blocks, label = connected_components(sp.csr_matrix(a), directed=False)
    return sorted(members(label, n_blocks), key=lambda idx: int(idx[0]))


class BlockFactor:
    """``A x = b`` by the factors of ``A``'s independent blocks (module docstring).

    Parameters
    ----------
    a
        The square sparse symmetric matrix, positive definite (factorised without pivoting;
        an unsymmetric one, or one with a pivot that is not positive, raises ``ValueError``).
    comm
        The ranks that share the solves (:mod:`pdfem.parallel.comm`); default one process.
    """

    def __init__(self, a: sp.spmatrix, comm=SerialComm()) -> None:
        a = sp.csr_matrix(a)
        scale = abs(a).max() if a.nnz else 0.0
        if a.nnz and abs(a - a.T).max() > 1e-12 * scale:
            raise ValueError("BlockFactor needs a symmetric matrix (L D L^T factors)")
        self.n = a.shape[0]
        self.blocks = independent_blocks(a)
        nnz = [a[idx].nnz for idx in self.blocks]
        self.dealt = Dealt(nnz, comm)
        self._factor(a)

    def _factor(self, a: sp.csr_matrix) -> None:
        """The ``L D L^T`` factors of this rank's blocks, flat (:mod:`pdfem.fem.ldl_kernels`):
        SuperLU with the minimum-degree ordering of ``A + A^T``, its symmetric mode and no
        pivoting, then ``L`` without its unit diagonal and ``D = diag(U)``."""
        n_b = [len(idx) for idx in self.blocks]
        # row indices are block-local: 16 bits where every block fits, a fifth fewer bytes
        # per entry of L than 32 (a solve streams L: 22 % faster on the milling blades)
        index = np.uint16 if max(n_b, default=0) <= ROWS_16_BITS else np.int32
        self._dof_ptr = np.concatenate([[0], np.cumsum(n_b)]).astype(np.int64)
        self._order = np.zeros(self.n, dtype=np.int64)
        self._diag = np.ones(self.n)
        col_ptr, rows, vals = [], [], []
        self._col_at = np.zeros(len(self.blocks), dtype=np.int64)
        base, at = 0, 0
        for k in self.dealt.mine:
            idx = self.blocks[k]
            lu = spla.splu(a[idx][:, idx].tocsc(), permc_spec="MMD_AT_PLUS_A",
                           diag_pivot_thresh=0.0, options={"SymmetricMode": True})
            if not np.array_equal(lu.perm_r, lu.perm_c):
                raise ValueError("BlockFactor: SuperLU permuted rows and columns differently")
            lo = self._dof_ptr[k]
            # DOF idx[i] sits at the factor's position perm_c[i] (Pr A Pc = L U, Pr = Pc^T)
            self._order[lo:lo + len(idx)] = idx[np.argsort(lu.perm_c)]
            d = lu.U.diagonal()
            if not np.all(d > 0.0):
                raise ValueError("BlockFactor: the matrix is not positive definite (a pivot "
                                 f"of {d.min():.3g}); an implicit step's matrix M + dt^2/4 K "
                                 "is, unless a spinning structure's spin softening outweighs "
                                 "its mass at that step (omega dt / 2 near 1 or more)")
            self._diag[lo:lo + len(idx)] = d
            low = sp.tril(lu.L, k=-1).tocsc()
            low.sort_indices()
            self._col_at[k] = at
            col_ptr.append(low.indptr.astype(np.int64) + base)
            rows.append(low.indices.astype(index))
            vals.append(low.data.astype(np.float64))
            at += len(idx) + 1
            base += low.nnz
        self._col_ptr = (np.concatenate(col_ptr) if col_ptr
                         else np.zeros(0, dtype=np.int64))
        self._rows = np.concatenate(rows) if rows else np.zeros(0, dtype=index)
        self._vals = np.concatenate(vals) if vals else np.zeros(0)

    @property
    def nbytes(self) -> int:
        """Bytes of this rank's factors: ``L``'s values, row indices and column pointers, ``D``."""
        return self._vals.nbytes + self._rows.nbytes + self._col_ptr.nbytes + self._diag.nbytes

    def solve(self, b: np.ndarray, blocks: np.ndarray | None = None) -> np.ndarray:
        """``x`` with ``A x = b``; ``b`` of shape (n,) or (n, k). ``blocks``: the blocks
        (ascending) outside which ``b`` is zero, when known (their solution is zero there;
        default: any). Collective when the blocks are split over ranks (every rank calls it
        with the same ``b`` and ``blocks``); each rank needs ``b`` on its own blocks only."""
        x, mine = self.solve_mine(b, blocks)
        if not self.dealt.shared:
            return x
        flat = x.reshape(self.n, -1)
        for k, part in self.dealt.everyone([flat[self.blocks[k]] for k in mine], blocks):
            flat[self.blocks[k]] = part
        return x

    def solve_mine(self, b: np.ndarray, blocks: np.ndarray | None = None
                   ) -> tuple[np.ndarray, list[int]]:
        """:meth:`solve` on this rank's blocks (of ``blocks``) only, without sharing: ``x``
        (zero on the other blocks) and the blocks solved."""
        b = np.asarray(b, dtype=np.float64)
        rhs = np.ascontiguousarray(b.reshape(self.n, -1).T)     # one right-hand side a row
        mine = self.dealt.mine_of(blocks)
        todo = np.array(mine, dtype=np.int64)
        x = np.zeros(rhs.shape)
        parallel = len(todo) > 1 and numba.get_num_threads() > 1
        solve_blocks(parallel, todo, self._dof_ptr, self._order, self._col_at,
                     self._col_ptr, self._rows, self._vals, self._diag, rhs, x)
        return np.ascontiguousarray(x.T).reshape(b.shape), mine
