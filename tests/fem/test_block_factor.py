"""A matrix factorised by its independent blocks solves as the whole matrix does, on 1 and 2 ranks.

References: ``scipy.sparse.linalg.spsolve`` of the whole matrix (to round-off); the serial
solve of the same blocks (bit for bit, on 2 ranks, where each rank solves its own blocks and
the parts are shared); 16-bit row indices against 32-bit ones (bit for bit); a zero
right-hand side of a block gives exactly zero there; the longest-first dealing of blocks to
ranks (Graham's LPT rule) by hand.
"""

from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from pdfem.fem.block_factor import BlockFactor, independent_blocks
from pdfem.parallel.deal import deal

from support.mpi import run_ranks


def blocky_spd(sizes=(7, 5, 9), seed=0) -> tuple[sp.csr_matrix, list[np.ndarray]]:
    """A symmetric positive-definite matrix of independent blocks of ``sizes``, its DOFs
    shuffled so that no block is contiguous; and the DOFs of each block."""
    rng = np.random.default_rng(seed)
    parts = []
    for n in sizes:
        b = sp.random(n, n, density=0.4, random_state=rng)
        parts.append((b + b.T + n * sp.identity(n)).toarray())
    a = sp.block_diag(parts).tocsr()
    perm = rng.permutation(a.shape[0])
    inv = np.argsort(perm)
    dofs = np.split(np.arange(a.shape[0]), np.cumsum(sizes)[:-1])
    return a[perm][:, perm].tocsr(), [np.sort(inv[d]) for d in dofs]


def test_blocks_are_the_connected_parts_in_order_of_their_first_dof():
    a, dofs = blocky_spd()
    found = independent_blocks(a)
    expected = sorted(dofs, key=lambda d: d[0])
    assert len(found) == 3
    for f, e in zip(found, expected):
        assert np.array_equal(f, e)


def test_solve_matches_the_whole_matrix():
    a, _ = blocky_spd()
    rng = np.random.default_rng(1)
    f = BlockFactor(a)
    b = rng.standard_normal(a.shape[0])
    assert np.allclose(f.solve(b), spla.spsolve(a.tocsc(), b), rtol=1e-12, atol=1e-14)
    bb = rng.standard_normal((a.shape[0], 4))
    assert np.allclose(f.solve(bb), spla.spsolve(a.tocsc(), bb), rtol=1e-12, atol=1e-14)


def test_a_zero_right_hand_side_block_is_exactly_zero():
    a, dofs = blocky_spd()
    b = np.zeros(a.shape[0])
    b[dofs[1]] = 1.0
    x = BlockFactor(a).solve(b)
    assert not np.any(x[dofs[0]]) and not np.any(x[dofs[2]])
    assert np.allclose(x, spla.spsolve(a.tocsc(), b), rtol=1e-12, atol=1e-14)
    # told where b is non-zero (the factor's block of dofs[1]), only that block is solved:
    # the same bits
    f = BlockFactor(a)
    k = [i for i, idx in enumerate(f.blocks) if np.array_equal(idx, dofs[1])]
    assert np.array_equal(f.solve(b, np.array(k)), x)


def test_largest_block_first_to_the_least_loaded_rank():
    # 5 -> rank 0; 4 -> rank 1; 3 -> rank 1 (4 < 5); 3 -> rank 0 (5 < 7): loads 8 and 7
    assert deal(np.array([5.0, 4.0, 3.0, 3.0]), 2).tolist() == [0, 1, 1, 0]
    assert deal(np.array([1.0, 1.0]), 3).tolist() == [0, 1]
    assert deal(np.array([2.0]), 1).tolist() == [0]


SCRIPT = textwrap.dedent('''
    import sys
    import numpy as np
    sys.path[:0] = [sys.argv[1], sys.argv[2]]
    from test_block_factor import blocky_spd
    from pdfem.fem.block_factor import BlockFactor
    from pdfem.parallel.comm import SerialComm, world
    comm = world()
    a, dofs = blocky_spd(sizes=(7, 5, 9, 6))
    rng = np.random.default_rng(2)
    b = rng.standard_normal(a.shape[0])
    bb = rng.standard_normal((a.shape[0], 3))
    split, serial = BlockFactor(a, comm), BlockFactor(a, SerialComm())
    assert split._vals.size < serial._vals.size, "each rank factorises only its own blocks"
    for rhs in (b, bb):
        assert np.array_equal(split.solve(rhs), serial.solve(rhs)), "not the serial bits"
    on_two = np.zeros_like(b)   # non-zero on the factor's blocks 0 and 1 (one on each rank)
    on_two[split.blocks[0]], on_two[split.blocks[1]] = b[split.blocks[0]], b[split.blocks[1]]
    assert np.array_equal(split.solve(on_two, np.array([0, 1])), serial.solve(on_two))
    one = BlockFactor(a[dofs[0]][:, dofs[0]], comm)   # one block: solved on every rank
    assert one.dealt.owner.tolist() == [comm.rank] and np.array_equal(one.solve(b[dofs[0]]),
                                            BlockFactor(a[dofs[0]][:, dofs[0]]).solve(b[dofs[0]]))
    owned = comm.gather(split.dealt.mine)
    if comm.rank == 0:
        print("ok", owned)
''')


def test_two_ranks_solve_their_own_blocks_and_agree_with_one_bit_for_bit(tmp_path):
    script = tmp_path / "blocks.py"
    script.write_text(SCRIPT)
    here = Path(__file__).parent
    r = run_ranks(2, sys.executable, script, here, here.parent, timeout=300)
    # each rank factorised the blocks dealt to it by their non-zeros, and only those
    a, _ = blocky_spd(sizes=(7, 5, 9, 6))
    owner = deal(np.array([a[d].nnz for d in independent_blocks(a)], dtype=float), 2)
    expected = [np.flatnonzero(owner == rank).tolist() for rank in (0, 1)]
    assert r.stdout.split("ok", 1)[1].strip() == str(expected)
    assert sorted(expected) == [[0, 3], [1, 2]]   # two blocks each


def test_the_factors_solve_on_one_and_on_two_threads_to_the_same_bits():
    """The L D L^T solves run one block per thread: the thread count changes no bit; and they
    solve the system (residual to round-off, reference ``spsolve``)."""
    import numba
    a, _ = blocky_spd(sizes=(40, 35, 50, 45), seed=3)
    f = BlockFactor(a)
    b = np.random.default_rng(4).standard_normal((a.shape[0], 2))
    threads = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = f.solve(b)
    finally:
        numba.set_num_threads(threads)
    assert np.array_equal(f.solve(b), one)
    assert np.allclose(one, spla.spsolve(a.tocsc(), b), rtol=1e-12, atol=1e-14)
    assert np.abs(a @ one - b).max() < 1e-12 * np.abs(b).max()


def test_16_bit_row_indices_solve_to_the_bits_of_32_bit_ones(monkeypatch):
    """Blocks that fit keep their factor's row indices in 16 bits: the same solution bit for
    bit as 32-bit indices (a block above the limit, forced here, keeps 32)."""
    import pdfem.fem.block_factor as block_factor
    a, _ = blocky_spd(sizes=(40, 35, 50, 45), seed=5)
    b = np.random.default_rng(6).standard_normal((a.shape[0], 3))
    short = BlockFactor(a)
    monkeypatch.setattr(block_factor, "ROWS_16_BITS", 49)
    wide = BlockFactor(a)
    assert short._rows.dtype == np.uint16 and wide._rows.dtype == np.int32
    assert short.nbytes < wide.nbytes
    assert np.array_equal(short.solve(b), wide.solve(b))
    assert np.array_equal(short.solve(b[:, 0]), wide.solve(b[:, 0]))


def test_an_unsymmetric_matrix_is_refused():
    a, _ = blocky_spd()
    a = a.tolil()
    a[0, 1] += 1.0
    with pytest.raises(ValueError, match="symmetric"):
        BlockFactor(a.tocsr())


def test_many_right_hand_sides_together_give_each_one_s_bits_alone():
    """Right-hand sides solved together (a probe's batch) get the bits each gets alone."""
    a, _ = blocky_spd(sizes=(30, 25, 40), seed=5)
    f = BlockFactor(a)
    b = np.random.default_rng(6).standard_normal((a.shape[0], 5))
    b[:, 2] = 0.0
    together = f.solve(b)
    for c in range(b.shape[1]):
        assert np.array_equal(together[:, c], f.solve(b[:, c]))
    assert not np.any(together[:, 2])


def test_a_matrix_that_is_not_positive_definite_is_refused():
    """Without pivoting, only a positive definite matrix is factorised: a symmetric one with a
    negative eigenvalue (here a negative diagonal block) raises instead of solving silently."""
    a, dofs = blocky_spd()
    a = a.tolil()
    for i in dofs[1]:
        a[i, i] = -a[i, i]
    with pytest.raises(ValueError, match="not positive definite"):
        BlockFactor(a.tocsr())


def _full_pass(f: BlockFactor, b: np.ndarray) -> np.ndarray:
    """The three passes of :mod:`pdfem.fem.ldl_kernels` in Python, every column of the forward
    pass taken (no skipping of zero entries): the reference bits."""
    x = np.zeros_like(b)
    for k in range(len(f.blocks)):
        lo, hi = f._dof_ptr[k], f._dof_ptr[k + 1]
        order, cp = f._order[lo:hi], f._col_at[k]
        y = b[order].copy()
        for j in range(hi - lo):
            for p in range(f._col_ptr[cp + j], f._col_ptr[cp + j + 1]):
                y[f._rows[p]] -= f._vals[p] * y[j]
        y = y / f._diag[lo:hi]
        for j in range(hi - lo - 1, -1, -1):
            s = y[j]
            for p in range(f._col_ptr[cp + j], f._col_ptr[cp + j + 1]):
                s -= f._vals[p] * y[f._rows[p]]
            y[j] = s
        x[order] = y
    return x


def test_a_sparse_right_hand_side_skips_columns_and_keeps_the_full_pass_bits():
    """The forward pass skips the columns whose entry is zero (a contact impulse at a few
    DOFs); reference: the same passes with every column taken (:func:`_full_pass`)."""
    a, dofs = blocky_spd(sizes=(30, 25), seed=4)
    f = BlockFactor(a)
    b = np.zeros(a.shape[0])
    b[dofs[0][[3, 17]]] = [1.5, -0.25]
    x = f.solve(b)
    assert np.count_nonzero(x[dofs[0]]) == len(dofs[0]) and not np.any(x[dofs[1]])
    assert np.array_equal(x, _full_pass(f, b))
    bb = np.zeros((a.shape[0], 2))
    bb[dofs[0][5], 0] = bb[dofs[1][2], 1] = 1.0
    assert np.array_equal(f.solve(bb), np.column_stack([_full_pass(f, bb[:, 0]),
                                                        _full_pass(f, bb[:, 1])]))
