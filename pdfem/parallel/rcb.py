"""Recursive coordinate bisection of particles spread over MPI ranks, without gathering them.

Used to re-partition a split ice body as it moves (:mod:`pdfem.pd.layout.rebalance`). Each rank holds
some particles: current positions (m), global numbers and weights (their work: the bond count).
The K ranks are cut recursively as :func:`pdfem.parallel.partition.rcb_partition` does: a piece
given n ranks is cut across its longest extent so that the left side, with floor(n/2) ranks,
gets floor(n/2)/n of the piece's weight. All pieces of one level are cut together.

The cut is an exact weighted selection by radix: each particle gets a key (its coordinate along
the axis, as an order-preserving unsigned integer, then its global number, so the order is total
and ties on a lattice plane are broken by number), and the cut key is found a byte at a time
from the weighted counts of the next byte over all ranks (one all-gather of a 256-entry
histogram per piece per byte). Weights are integers, so the sums are exact whatever the rank
order: the partition depends only on the set of (position, number, weight), never on which
rank holds a particle, so it does not depend on the previous partition (history). No rank holds
more than its own particles and K x 256 counts. Cost per level: 8 + ceil(bits(N) / 8)
all-gathers of at most K/2 x 256 counts, plus O(n_local) work per byte.
"""

from __future__ import annotations

import numpy as np

_SIGN = np.uint64(1 << 63)


def sortable_keys(x: np.ndarray) -> np.ndarray:
    """(M,) uint64 keys ordered as the float64 values ``x`` (m) are (negative zero below zero)."""
    bits = np.ascontiguousarray(x, dtype=np.float64).view(np.uint64)
    return np.where(bits & _SIGN, ~bits, bits | _SIGN)


def _pieces_extent(x: np.ndarray, piece: np.ndarray, n_pieces: int, comm) -> np.ndarray:
    """(n_pieces,) axis (0, 1, 2) of the longest extent of each piece over all ranks."""
    lo = np.full((n_pieces, 3), np.inf)
    hi = np.full((n_pieces, 3), -np.inf)
    for k in range(3):
        np.minimum.at(lo[:, k], piece, x[:, k])
        np.maximum.at(hi[:, k], piece, x[:, k])
    parts = comm.allgather((lo, hi))
    lo = np.min([p[0] for p in parts], axis=0)
    hi = np.max([p[1] for p in parts], axis=0)
    ext = np.where(np.isfinite(hi - lo), hi - lo, 0.0)
    return np.argmax(ext, axis=1)


def _select(keys: list[tuple[np.ndarray, int]], piece: np.ndarray, weight: np.ndarray,
            target: np.ndarray, comm) -> np.ndarray:
    """Which particles go left: in each piece, those before the cut key in key order, the cut
    chosen where the running weight reaches ``target`` (the particle at the cut goes left if
    at least half of its weight is needed). ``keys``: (uint64 word, bytes used from its top)
    pairs, most significant first (all ranks the same). Collective."""
    n_pieces = len(target)
    left = np.zeros(len(piece), dtype=bool)
    open_ = np.ones(len(piece), dtype=bool)  # still undecided
    need = target.astype(np.float64).copy()  # weight still to put left, per piece
    w = weight.astype(np.float64)
    for word, nbytes in keys:
        for shift in range(56, 56 - 8 * nbytes, -8):
            idx = np.flatnonzero(open_)
            byte = ((word[idx] >> np.uint64(shift)) & np.uint64(255)).astype(np.int64)
            slot = piece[idx] * 256 + byte
            hist = np.bincount(slot, weights=w[idx], minlength=n_pieces * 256)
            hist = np.sum(comm.allgather(hist), axis=0).reshape(n_pieces, 256)  # exact: ints
            cum = np.cumsum(hist, axis=1)
            # first byte whose running weight reaches the need (256: none, all go left)
            cut = np.where(need > 0, (cum < need[:, None]).sum(axis=1), -1)
            cut = np.minimum(cut, 255)
            before = np.where(cut > 0, np.take_along_axis(cum, np.maximum(cut - 1, 0)[:, None],
                                                          axis=1)[:, 0], 0.0)
            need = np.where(cut >= 0, need - before, need)
            c = cut[piece[idx]]
            left[idx[byte < c]] = True
            open_[idx[byte != c]] = False
    # one particle per piece may remain (keys are unique): left if half its weight is needed
    idx = np.flatnonzero(open_)
    left[idx] = need[piece[idx]] >= 0.5 * w[idx]
    return left


def rcb_owners(x: np.ndarray, gid: np.ndarray, weight: np.ndarray, n_parts: int, comm,
               n_global: int) -> np.ndarray:
    """The new owner rank (int32, (M,)) of each of this rank's particles by weighted recursive
    coordinate bisection over ``n_parts`` ranks. Collective.

    Parameters
    ----------
    x
        (M, 3) current positions (m) of this rank's particles.
    gid
        (M,) their global numbers (unique over all ranks): the tie-break.
    weight
        (M,) their non-negative integer weights (work, e.g. bond counts).
    n_parts
        Number of ranks to cut into.
    comm
        The communicator (:mod:`pdfem.parallel.comm`).
    n_global
        Number of particles over all ranks (sets the number of digits of the tie-break).
    """
    x = np.ascontiguousarray(x, dtype=np.float64).reshape(-1, 3)
    gid = np.asarray(gid, dtype=np.int64)
    weight = np.asarray(weight, dtype=np.int64)
    # pieces of a level: (first rank, ranks); piece[p] = index of particle p's piece
    pieces = [(0, int(n_parts))]
    piece = np.zeros(len(x), dtype=np.int64)
    nbytes = _gid_bytes(n_global)
    gid_key = gid.astype(np.uint64) << np.uint64(64 - 8 * nbytes)
    while any(n > 1 for _, n in pieces):
        axis = _pieces_extent(x, piece, len(pieces), comm)
        totals = np.bincount(piece, weights=weight.astype(np.float64), minlength=len(pieces))
        totals = np.sum(comm.allgather(totals), axis=0)
        share = np.array([(n // 2) / n for _, n in pieces])
        target = np.floor(totals * share + 0.5)
        coord = x[np.arange(len(x)), axis[piece]] if len(x) else np.zeros(0)
        left = _select([(sortable_keys(coord), 8), (gid_key, nbytes)], piece, weight, target, comm)
        # single-rank pieces keep everything "left"
        nxt, index = [], []
        for first, n in pieces:
            if n == 1:
                index.append((len(nxt), len(nxt)))
                nxt.append((first, 1))
            else:
                index.append((len(nxt), len(nxt) + 1))
                nxt += [(first, n // 2), (first + n // 2, n - n // 2)]
        index = np.array(index, dtype=np.int64).reshape(-1, 2)
        piece = np.where(left, index[piece, 0], index[piece, 1]) if len(x) else piece
        pieces = nxt
    firsts = np.array([f for f, _ in pieces], dtype=np.int32)
    return firsts[piece] if len(x) else np.zeros(0, dtype=np.int32)


def _gid_bytes(n_global: int) -> int:
    """Bytes needed for the global numbers 0 .. n_global - 1 (at least one)."""
    return max(1, (max(int(n_global) - 1, 1).bit_length() + 7) // 8)
