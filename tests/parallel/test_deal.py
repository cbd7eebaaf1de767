"""Pieces of work dealt over ranks: every rank gets every piece's result, in piece order, from
the rank that made it; pickled (:meth:`Dealt.everyone`) or as one float64 buffer
(:meth:`Dealt.everyone_arrays`, an MPI_Allgatherv), with the same values bit for bit.

Reference: each piece's result is a function of the piece alone, so every rank can compute
what it must receive; on 3 ranks, pieces of unequal sizes, all of them and a subset.
"""

from __future__ import annotations

import textwrap

import numpy as np

from pdfem.parallel.deal import Dealt

from support.mpi import script_says

SIZES = [5, 0, 7, 3, 11, 2]


def result(k: int) -> np.ndarray:
    """Piece ``k``'s result: ``SIZES[k]`` values no other piece has."""
    return np.sin(np.arange(SIZES[k]) + 10.0 * k) * 10.0 ** k


def test_one_rank_keeps_its_own_results():
    dealt = Dealt(SIZES)
    got = dealt.everyone_arrays([result(k) for k in dealt.mine], SIZES)
    assert [k for k, _ in got] == list(range(len(SIZES)))
    assert all(np.array_equal(part, result(k)) for k, part in got)


SCRIPT = textwrap.dedent('''
    import sys
    import numpy as np
    sys.path[:0] = [sys.argv[1], sys.argv[2]]
    from test_deal import SIZES, result
    from pdfem.parallel.comm import world
    from pdfem.parallel.deal import Dealt
    comm = world()
    dealt = Dealt(SIZES, comm)
    for pieces in (None, [1, 2, 4, 5]):
        mine = dealt.mine_of(pieces)
        fast = dealt.everyone_arrays([result(k) for k in mine], SIZES, pieces)
        slow = dealt.everyone([result(k) for k in mine], pieces)
        want = list(range(len(SIZES))) if pieces is None else pieces
        assert [k for k, _ in fast] == [k for k, _ in slow] == sorted(want, key=lambda k: (
            dealt.owner[k], k)), [k for k, _ in fast]
        for (k, a), (_, b) in zip(fast, slow):
            assert np.array_equal(a, result(k)) and np.array_equal(b, result(k)), k
    if comm.rank == 0:
        print("ok", dealt.owner.tolist())
''')


def test_three_ranks_get_every_piece_as_buffers_and_pickled(tmp_path):
    # largest first to the least loaded: 4 (11) -> 0, 2 (7) -> 1, 0 (5) -> 2, 3 (3) -> 2,
    # 5 (2) -> 1, 1 (0) -> 2
    assert script_says(SCRIPT, 3, tmp_path, __file__) == "[2, 2, 1, 2, 0, 1]"
