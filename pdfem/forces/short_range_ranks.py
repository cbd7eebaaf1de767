"""Short-range contact across MPI ranks: each rank searches its own particles and its contact halo.

:class:`DistributedSearch` is the search of a :class:`pdfem.forces.short_range.ShortRangeContact`
whose bodies are split over MPI ranks (:class:`pdfem.pd.layout.halo.DistributedIce`, which carry
the communicator). Each rank holds its owned particles and their contact ghosts
(:class:`pdfem.forces.short_range_halo.ContactHalo`: a Verlet skin, refreshed only when some
particle has moved far enough; between refreshes only the ghosts' positions are exchanged) in
global order (body offset + index in the body, the serial order), and runs the serial kernels
(:mod:`pdfem.forces.short_range_kernels`) on them, on the cells of the serial run's grid (box
and dense/folded choice from the global extent and particle count, which the halo's one
collective per call provides). The tables are local: the cells of the local particles' box when
that is small (at most ``DENSE_CELLS_PER_PARTICLE`` cells per local particle), else a sparse
table of the occupied buckets; either way sized from the local particle count, never the global
one. The stable sort keeps the local particles in the serial sorted order, so every owned
particle meets its partners in the serial order and its force is the serial one bit for bit.
Each pair's potential is counted on the rank that owns the pair's first particle (in sorted
order), so it is counted once over the ranks.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pdfem.forces.short_range_halo import ContactHalo
from pdfem.forces.short_range_kernels import NO_SHIFT, add_owned, counted_pairs, sum_pairs
from pdfem.geometry.cell_hash import bounding_box

if TYPE_CHECKING:
    from pdfem.forces.short_range import ShortRangeContact


class DistributedSearch:
    """The search of a :class:`ShortRangeContact` whose bodies are split over MPI ranks
    (:class:`pdfem.pd.layout.halo.DistributedIce`), with the serial run's forces, bit for bit.

    Every call, each rank

    1. updates its contact halo (one collective; a refresh when due, else the ghosts'
       positions from their owners);
    2. searches its owned particles and ghosts, in global order, on the serial run's cells
       with a local table and the serial kernels: each owned particle meets its partners in the
       serial order, so its force is summed exactly as in the serial run;
    3. keeps the forces of its owned particles, and counts a pair (and its potential) if it
       owns the pair's first particle (:attr:`n_counted`; sums over ranks in
       :meth:`ShortRangeContact.potential_energy` and :meth:`ShortRangeContact.total_pairs`).
    """

    def __init__(self, contact: ShortRangeContact, stiffness: list, radius: list) -> None:
        self.contact = contact
        bodies = contact.bodies
        self.comm = bodies[0].comm
        self.halo = ContactHalo(bodies, contact.offsets, stiffness, radius, contact.cell_size,
                                self.comm)
        self.n_counted = 0
        self.grid_buckets = 0  # buckets of the serial run's grid (not allocated here)

    @property
    def n_ghosts(self) -> int:
        """Ghost particles held by this rank."""
        return self.halo.n_ghosts

    def search(self) -> float:
        """Find the pairs of the local particles; returns the potential (J) of the pairs this
        rank counts. Collective."""
        c, h = self.contact, self.halo
        c._n_touched = 0
        self.n_counted = 0
        if c.n < 2:
            return 0.0
        glo, ghi = h.update()
        m = h.m
        dims, pad, fold, nb = c._grid(glo, ghi, c.n)  # the serial run's grid
        self.grid_buckets = nb
        if m < 2:
            return 0.0
        c._reserve(m)
        y = h.y
        shift, sparse = NO_SHIFT, True
        if c.dense:  # the cells of the local particles' box, if that table is small
            llo, lhi, _ = bounding_box(y)
            inv_h = 1.0 / c.cell_size
            first = np.array([int(min((llo[k] - glo[k]) * inv_h, float(dims[k] - 1)))
                              for k in range(3)], dtype=np.int64)
            last = np.array([int(min((lhi[k] - glo[k]) * inv_h, float(dims[k] - 1)))
                             for k in range(3)], dtype=np.int64)
            box = last - first + 3
            if float(np.prod(box)) <= c.budget(m):
                shift, sparse, fold, nb = first, False, box, int(np.prod(box))
        c.n_buckets = m if sparse else nb
        n_chunks = max(1, min(c._chunks_wanted, m))
        chunk_ptr = (np.arange(n_chunks + 1, dtype=np.int64) * m) // n_chunks
        counts = np.zeros(n_chunks, dtype=np.int64)
        c._scan(y, glo, dims, pad, fold, nb, h.x0, h.vol, h.stiffness, h.radius, h.body,
                chunk_ptr, counts, shift, sparse)
        c._counts = counts
        n_pairs, energy = counted_pairs(counts, c._cap, c._pair, c._val, h.owned)
        self.n_counted = int(n_pairs)
        if counts.sum():
            nt, _ = sum_pairs(counts, c._cap, c._pair, c._val, h.vol, c._acc, c._mark,
                              c._touched)
            c._n_touched = nt
        return float(energy)

    def add_into(self, fs: list) -> None:
        """Add the last search's force density of each owned particle into ``fs`` (one local
        array per body)."""
        c, h = self.contact, self.halo
        nt = c._n_touched
        if nt == 0:
            return
        k = 0
        for f, o in zip(fs, h.own):
            add_owned(f, o, h.own_pos[k:k + len(o)], c._acc, c._touched, nt, c._mark)
            k += len(o)
