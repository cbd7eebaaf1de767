"""Race-free, deterministic parallel loops over a unique-pair list: blocks and overflow buffers.

The pair kernels (:mod:`pdfem.pd.bonds.pair_loop`) loop over unique bonds i < j grouped by i (CSR:
``row_ptr`` int64 (N+1,), ``nbr`` int32 (P,)) and add each bond's contribution to both ends.
To do that in parallel without data races, the particles (rows) are cut into *blocks*
(:class:`PairWorkspace`); a ``prange`` over blocks accumulates the i side of each row in
registers and writes the j side directly into the output when j lies in the block's own rows
and otherwise into the block's overflow buffer (pairs point forwards, j > i, so only later rows
can be hit from outside). A second ``prange`` over blocks adds the overflow buffers of the
earlier blocks in fixed block order (:func:`add_overflow1`, :func:`add_overflow3`).

The blocks are fixed ranges of *global* particle numbers (:func:`block_bounds`: a function of
the whole body's particle and bond counts and of its bonds' reach in the numbering, never of the
thread or rank count), and threads only share the blocks out. Each particle's sums are therefore
taken in one fixed order: its own row's bonds in row order, then the bonds from earlier rows of
its block in row order, then each earlier block's overflow in block order. A rank of a split
body holds every bond of its owned particles, in the global order, so it takes each owned
particle's sums in the same order as the whole body does: the same bits on any number of
threads and ranks. A body with fewer than ``SERIAL_BELOW_PAIRS`` bonds is one block and runs a
same kernels on one thread (:func:`twin`).
"""

from __future__ import annotations

import numpy as np

from pdfem.parallel.kernels import SERIAL_BELOW_PARTICLES
from pdfem.pd.bonds.chunk_kernels import chunk_split, max_reach, pairs_forward
from pdfem.pd.bonds.data import Blocks

# Below these sizes the kernels run on one thread: a parallel region costs more than the
# work, and a lot more when the machine is oversubscribed (the threads wait at a barrier for a
# descheduled peer).
SERIAL_BELOW_PAIRS = 50_000
PAIRS_PER_BLOCK = 1 << 16
"""Bonds per block (about 1,000 interior particles): bodies from twice this share out."""
MAX_BLOCKS = 64
"""Most blocks of a body: enough to balance 8 threads to 1/8 of a block."""


def block_bounds(n_global: int, n_pairs: int, reach: int) -> np.ndarray:
    """The first global particle number of each block and the end, (B+1,) int64: B blocks of
    equal particle count. B = 1 below ``SERIAL_BELOW_PAIRS`` bonds; else about one block per
    ``PAIRS_PER_BLOCK`` bonds, at most ``MAX_BLOCKS`` and at most ``n_global / (6 reach)``
    (``reach`` = the largest j - i of the bonds in the numbering: a block's rows within the
    reach of its end write their partners' sums into its overflow buffer, the slower path, so
    blocks are kept six reaches long: measured on a 100^3 block, 4 blocks run the pair loop as
    fast as 2, 12 blocks 23 % slower), rounded down to a multiple of 4 (or 2) so that 2 or 4
    threads get equal shares."""
    b = 1
    if n_pairs >= SERIAL_BELOW_PAIRS:
        b = min(MAX_BLOCKS, n_pairs // PAIRS_PER_BLOCK, n_global // max(6 * int(reach), 1))
        b = b - b % 4 if b >= 4 else min(max(b, 1), 2)
    return (np.arange(b + 1, dtype=np.int64) * int(n_global)) // b


class PairWorkspace:
    """Chunk layout and scratch buffers for the pair loops over one pair list.

    Build it once per pair list and pass it to every kernel call (the kernels make a temporary
    one when none is given).

    Parameters
    ----------
    row_ptr, nbr
        The CSR pair list (int64 (N+1,), int32 (P,)); every pair must have i < nbr[k] < N.
    n_chunks
        Number of blocks C of equal particle count, for tests (default: :func:`block_bounds`
        of this pair list). With C = 1 the kernels run on one thread.
    bounds, gid
        The global blocks (:func:`block_bounds` of the whole body) and the global numbers of
        the local particles (ascending), for a rank's part of a body (or a body whose blocks are
        fixed by the whole body's figures: :mod:`pdfem.pd.layout.blocks`).
    keep_bond_length
        Let :func:`pdfem.pd.bonds.pair_loop.dilatation_and_forces` keep the current bond lengths
        between its two passes (8 bytes per pair of scratch, saves a square root per bond);
        False: no per-pair scratch at all.

    Attributes
    ----------
    chunk_ptr
        int64 (C+1,) first row of each block (the local rows of the global blocks).
    split
        int64 (C,) first row of each chunk with a partner beyond the chunk; the hot loops check
        for overflow only from there on.
    ov_ptr
        int64 (C+1,) offsets of each chunk's overflow rows in ``ov``; chunk c's overflow covers
        particles ``chunk_ptr[c+1] : chunk_ptr[c+1] + ov_ptr[c+1] - ov_ptr[c]``.
    ov
        float64 (ov_ptr[-1], 3) overflow buffer.
    coef
        float64 (N, 2) per-particle force coefficients (a, b of
        :func:`pdfem.pd.bonds.lps_law.force_coefficients`).
    aux
        float64 (N, 2) per-particle halves of the dilatation and of the strength factor that
        the failure test of a bond adds over its ends.
    bond_length
        float64 (P,) current bond lengths kept by
        :func:`pdfem.pd.bonds.pair_loop.dilatation_and_forces` (None until that is first called,
        and always None without ``keep_bond_length``).
    lengths_current
        Whether ``bond_length`` holds the lengths of the last fused step's pass (set there;
        whoever puts other positions or bonds in place without a step clears it).
    """

    def __init__(self, row_ptr: np.ndarray, nbr: np.ndarray, n_chunks: int | None = None,
                 keep_bond_length: bool = True, bounds: np.ndarray | None = None,
                 gid: np.ndarray | None = None):
        row_ptr = np.asarray(row_ptr)
        nbr = np.asarray(nbr)
        n = row_ptr.shape[0] - 1
        if n < 0 or row_ptr[0] != 0 or row_ptr[-1] != nbr.shape[0]:
            raise ValueError("row_ptr must start at 0 and end at the number of pairs len(nbr)")
        if not pairs_forward(row_ptr, nbr):
            raise ValueError(
                "the pair list must hold unique pairs i < j grouped by i (nbr[k] > i for k in "
                "row i, and every index below N)"
            )
        P = nbr.shape[0]
        gid = np.arange(n, dtype=np.int64) if gid is None else np.asarray(gid)
        if bounds is None:
            if n_chunks is None:
                bounds = block_bounds(n, P, max_reach(row_ptr, nbr, gid))
            else:
                c = max(1, min(int(n_chunks), max(n, 1)))
                bounds = (np.arange(c + 1, dtype=np.int64) * n) // c
        cb = np.searchsorted(gid, bounds, side="left").astype(np.int64)
        cb[0] = 0
        cb[-1] = n
        C = cb.shape[0] - 1
        ov_len = np.zeros(C, dtype=np.int64)
        for c in range(C):
            k0, k1 = row_ptr[cb[c]], row_ptr[cb[c + 1]]
            if k1 > k0:
                ov_len[c] = max(0, int(nbr[k0:k1].max()) + 1 - int(cb[c + 1]))
        self.n = n
        self.n_pairs = P
        self.n_chunks = C
        self.chunk_ptr = cb
        self.split = chunk_split(row_ptr, nbr, cb)
        self.ov_ptr = np.concatenate(([0], np.cumsum(ov_len))).astype(np.int64)
        self.ov = np.zeros((int(self.ov_ptr[-1]), 3))
        self.coef = np.empty((n, 2))
        self.aux = np.empty((n, 2))
        self.counts = np.zeros(C, dtype=np.int64)
        self.blocks = Blocks(cb, self.split, self.ov_ptr, self.ov, self.counts)
        self.crush = np.zeros(C)  # energy (J) each chunk's crushed bonds dissipated, last pass
        self.crush_dissipated = 0.0  # their sum in chunk order
        self.parallel = C > 1
        # per-particle loops (force coefficients) of a small body run serially even when the
        # pair loops are threaded: a parallel region over a few thousand particles costs more
        # than the work (2.3 ms per call in the demo at load 4, against microseconds serially)
        self.parallel_particles = self.parallel and n >= SERIAL_BELOW_PARTICLES
        self.bond_length: np.ndarray | None = None
        self.keep_bond_length = bool(keep_bond_length)
        self.lengths_current = False

    def bond_length_buffer(self) -> np.ndarray:
        """The (P,) float64 bond-length scratch of the fused step (allocated on first use)."""
        if self.bond_length is None:
            self.bond_length = np.empty(self.n_pairs)
        return self.bond_length

    def check(self, row_ptr: np.ndarray, nbr: np.ndarray) -> None:
        """Raise ValueError if this workspace was not built for a list of this size."""
        if row_ptr.shape[0] - 1 != self.n or nbr.shape[0] != self.n_pairs:
            raise ValueError(
                f"workspace built for {self.n} particles and {self.n_pairs} pairs, got "
                f"{row_ptr.shape[0] - 1} and {nbr.shape[0]}"
            )


def c_contiguous(a: np.ndarray, name: str) -> np.ndarray:
    """``a`` itself if C-contiguous (the kernels index flat views), else ValueError."""
    if not a.flags.c_contiguous:
        raise ValueError(f"{name} must be a C-contiguous array")
    return a


def workspace_for(ws: PairWorkspace | None, row_ptr: np.ndarray, nbr: np.ndarray) -> PairWorkspace:
    """``ws`` checked against the pair list, or a new workspace for it when ``ws`` is None."""
    if ws is None:
        return PairWorkspace(row_ptr, nbr)
    ws.check(row_ptr, nbr)
    return ws


