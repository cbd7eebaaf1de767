"""Short-range contact across MPI ranks: ghost exchange on the serial run's global grid.

:class:`DistributedSearch` is the search of a :class:`pdfem.forces.short_range.ShortRangeContact`
whose bodies are split over MPI ranks (:class:`pdfem.pd.distributed.DistributedIce`, which carry
the communicator). Each rank takes the particles of other ranks within 1.5 h of the box of its
own particles (fragments move, so these partners change every step; the static bond halo is not
used), orders its own particles and these ghosts by global index (body offset + index in the
body, the serial order) and runs the serial kernels (:mod:`pdfem.forces.short_range_kernels`) on
them, on the grid the serial run would use (box and dense/folded choice from the global extent
and particle count; a dense grid is cut down to the cells of the local particles, which keeps
their order, so a rank's table scales with its own particles). The stable counting sort keeps
the local particles in the serial sorted order, so every owned particle meets its partners in
the serial order and its force is the serial one bit for bit; each pair's potential is counted
on the rank that owns the pair's first particle, and the sums are over ranks.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pdfem.forces.short_range_kernels import (
    NO_SHIFT,
    NOT_FINITE,
    counted_pairs,
    sum_pairs,
)
from pdfem.geometry.cell_hash import bounding_box

if TYPE_CHECKING:
    from pdfem.forces.short_range import ShortRangeContact


class DistributedSearch:
    """The search of a :class:`ShortRangeContact` whose bodies are split over MPI ranks
    (:class:`pdfem.pd.distributed.DistributedIce`), with the serial run's forces, bit for bit.

    Every call, each rank

    1. shares the box of its owned particles (all bodies) with every rank, and sends each rank
       its owned particles within 1.5 h of that rank's box (global id and position): the
       *ghosts*, every partner an owned particle can have, wherever fragments have moved;
    2. searches its owned particles and ghosts, ordered by global id (body offset + index in
       the body, the serial order), on the serial run's cells (from the global extent and
       particle count; a dense table only over the local cells), with the serial kernels. The stable counting sort
       keeps the local particles in the serial sorted order, so each owned particle meets its
       partners in the same order and its force is summed exactly as in the serial run;
    3. keeps the forces of its owned particles, and counts a pair (and its potential) on the
       rank owning the pair's first particle, summed over ranks.
    """

    def __init__(self, contact: ShortRangeContact) -> None:
        self.contact = contact
        bodies = contact.bodies
        self.comm = bodies[0].comm
        self.own = [np.flatnonzero(b.owned) for b in bodies]
        self.own_gid = np.concatenate(
            [b.plan.local[o].astype(np.int64) + off
             for b, o, off in zip(bodies, self.own, contact.offsets[:-1])])
        self.margin = 1.5 * contact.cell_size
        self.n_ghosts = 0  # ghosts received by the last search
        self._own_pos = np.empty(0, dtype=np.int64)
        self._m = 0

    def search(self) -> float:
        c, comm = self.contact, self.comm
        c._n_touched = 0
        c.n_active = 0
        if c.n < 2:
            return 0.0
        y_own = np.concatenate([b.y[o] for b, o in zip(c.bodies, self.own)])
        if len(y_own):
            lo, hi, finite = bounding_box(y_own)
        else:
            lo, hi, finite = np.full(3, np.inf), np.full(3, -np.inf), True
        boxes = np.array(comm.allgather(np.concatenate([lo, hi, [0.0 if finite else 1.0]])))
        if boxes[:, 6].any():
            raise FloatingPointError(NOT_FINITE)
        glo = boxes[:, :3].min(axis=0)
        ghi = boxes[:, 3:6].max(axis=0)
        # ghosts: what every other rank needs of ours, and what we get
        P, me = comm.size, comm.rank
        sends = {}
        sent = np.zeros(P, dtype=np.int64)
        for q in range(P):
            if (q == me or len(y_own) == 0 or np.any(boxes[q, :3] - self.margin > hi)
                    or np.any(boxes[q, 3:6] + self.margin < lo)):
                continue  # nothing of ours is near rank q's particles
            inside = np.all((y_own >= boxes[q, :3] - self.margin)
                            & (y_own <= boxes[q, 3:6] + self.margin), axis=1)
            idx = np.flatnonzero(inside)
            if len(idx):
                buf = np.empty((len(idx), 4))
                buf[:, 0] = self.own_gid[idx]
                buf[:, 1:] = y_own[idx]
                sends[q] = buf
                sent[q] = len(idx)
        table = np.array(comm.allgather(sent)).reshape(P, P)
        recvs = {p: ((int(table[p, me]), 4), np.float64) for p in range(P)
                 if p != me and table[p, me] > 0}
        got = comm.exchange(sends, recvs) if (sends or recvs) else {}
        self.n_ghosts = int(sum(len(g) for g in got.values()))
        gid = np.concatenate([self.own_gid] + [got[p][:, 0].astype(np.int64) for p in sorted(got)])
        y = np.concatenate([y_own] + [got[p][:, 1:] for p in sorted(got)])
        order = np.argsort(gid, kind="stable")
        gid = gid[order]
        y = np.ascontiguousarray(y[order])
        m = len(gid)
        where = np.empty(m, dtype=np.int64)
        where[order] = np.arange(m)
        self._own_pos = where[:len(self.own_gid)]
        self._m = m
        owned = np.zeros(m, dtype=np.bool_)
        owned[self._own_pos] = True
        # the serial search on the local particles
        c._reserve(m)
        vol = c.vol[gid]
        dims, pad, fold, nb = c._grid(glo, ghi, c.n)
        n_pairs, energy = 0, 0.0
        if m >= 2:
            shift = NO_SHIFT
            if c.dense:  # only the cells of the local particles (same cells, same order)
                llo, lhi, _ = bounding_box(y)
                inv_h = 1.0 / c.cell_size
                first = np.array([int(min((llo[k] - glo[k]) * inv_h, float(dims[k] - 1)))
                                  for k in range(3)], dtype=np.int64)
                last = np.array([int(min((lhi[k] - glo[k]) * inv_h, float(dims[k] - 1)))
                                 for k in range(3)], dtype=np.int64)
                shift = first
                fold = last - first + 3
                nb = int(np.prod(fold))
            n_chunks = max(1, min(c._chunks_wanted, m))
            chunk_ptr = (np.arange(n_chunks + 1, dtype=np.int64) * m) // n_chunks
            counts = np.zeros(n_chunks, dtype=np.int64)
            c._scan(y, glo, dims, pad, fold, nb, c.x0[gid], vol, c.stiffness[gid],
                    c.radius[gid], c.body[gid], chunk_ptr, counts, shift)
            n_pairs, energy = counted_pairs(counts, c._cap, c._pair, c._val, owned)
            if counts.sum():
                nt, _ = sum_pairs(counts, c._cap, c._pair, c._val, vol, c._acc, c._mark,
                                  c._touched)
                c._n_touched = nt
        total = comm.allreduce_sum(np.array([float(n_pairs), energy]))
        c.n_active = int(total[0])
        return float(total[1])

    def add_into(self, fs: list) -> None:
        """Add the last search's force density of each owned particle into ``fs`` (one local
        array per body)."""
        c = self.contact
        nt = c._n_touched
        if nt == 0:
            return
        hit = np.zeros(self._m, dtype=np.bool_)
        hit[c._touched[:nt]] = True
        k = 0
        for f, o in zip(fs, self.own):
            pos = self._own_pos[k:k + len(o)]
            k += len(o)
            sel = hit[pos]
            f[o[sel]] += c._acc[pos[sel]]
