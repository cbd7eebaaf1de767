"""Independent pieces of work dealt out over the ranks: who does which, and everyone's results.

Some of a run's work falls into independent pieces that every rank would otherwise repeat: the
blocks of an implicit structure's matrix (:mod:`pdfem.fem.block_factor`), one per part that
meets the others only at held DOFs. :class:`Dealt` gives each piece to one rank (the largest
first, each to the rank with the least work so far: Graham's longest-processing-time rule) and
hands every rank all the pieces' results afterwards, in piece order, so the ranks go on with the
same bits. On one rank, or with a single piece, every rank does all of it and nothing is sent.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from pdfem.parallel.comm import SerialComm


def deal(work: np.ndarray, ranks: int) -> np.ndarray:
    """The rank of each piece: the largest ``work`` first, each to the rank with the least work
    so far (ties: the earlier piece first, the lower rank)."""
    owner = np.zeros(len(work), dtype=np.int64)
    load = np.zeros(ranks)
    for b in sorted(range(len(work)), key=lambda k: (-work[k], k)):
        r = int(np.argmin(load))
        owner[b] = r
        load[r] += work[b]
    return owner


class Dealt:
    """Pieces of work (their sizes ``work``, any unit) dealt over the ranks of ``comm``.

    Attributes
    ----------
    owner
        (P,) the rank that does each piece (this rank for every piece when nothing is dealt).
    mine
        The pieces this rank does, ascending.
    """

    def __init__(self, work: Sequence[float], comm=SerialComm()) -> None:
        work = np.asarray(work, dtype=np.float64)
        self.comm = comm
        self._shared = comm.size > 1 and len(work) > 1
        self.owner = (deal(work, comm.size) if self._shared
                      else np.full(len(work), comm.rank, dtype=np.int64))
        self.mine = [int(k) for k in np.flatnonzero(self.owner == comm.rank)]

    @property
    def shared(self) -> bool:
        """Whether the pieces are dealt out (several ranks and pieces), so that each rank does
        only its own."""
        return self._shared

    def everyone(self, parts: list, pieces: Sequence[int] | None = None
                 ) -> list[tuple[int, object]]:
        """``(piece, result)`` of every piece of ``pieces`` (ascending; default all), from each
        rank's ``parts`` (the results of its pieces among them, :meth:`mine_of`, in that
        order). Collective when pieces are dealt out (every rank passes the same ``pieces``)."""
        if not self._shared:
            return list(zip(self.mine_of(pieces), parts))
        return [(int(k), part)
                for ks, rank_parts in zip(self._by_rank(pieces), self.comm.allgather(parts))
                for k, part in zip(ks, rank_parts)]

    def everyone_arrays(self, parts: list[np.ndarray], sizes: Sequence[int],
                        pieces: Sequence[int] | None = None) -> list[tuple[int, np.ndarray]]:
        """:meth:`everyone` for float64 results whose lengths every rank knows (``sizes[k]`` for
        piece ``k``): one all-gather of their concatenation as a buffer, nothing pickled.
        ``parts`` are this rank's results (flat) of its pieces among ``pieces``, in that
        order. Collective when pieces are dealt out."""
        if not self._shared:
            return list(zip(self.mine_of(pieces), parts))
        by_rank = self._by_rank(pieces)
        counts = [int(sum(sizes[k] for k in ks)) for ks in by_rank]
        flat = self.comm.allgatherv(np.concatenate(parts) if parts else np.zeros(0), counts)
        out, at = [], 0
        for ks in by_rank:
            for k in ks:
                out.append((int(k), flat[at:at + sizes[k]]))
                at += sizes[k]
        return out

    def _by_rank(self, pieces: Sequence[int] | None) -> list[np.ndarray]:
        """The pieces of ``pieces`` (ascending; default all) that each rank does."""
        every = (np.arange(len(self.owner)) if pieces is None
                 else np.asarray(pieces, dtype=np.int64))
        return [every[self.owner[every] == rank] for rank in range(self.comm.size)]

    def mine_of(self, pieces: Sequence[int] | None = None) -> list[int]:
        """This rank's pieces among ``pieces`` (ascending; default all): :attr:`mine` there."""
        if pieces is None:
            return self.mine
        return [int(k) for k in pieces if self.owner[k] == self.comm.rank]
