"""Short-range repulsion between ice particles: contact of fragments and of separate ice bodies.

Peridynamic bonds act only between particles bonded at t = 0, so once bonds break, fragments
could pass through each other. The short-range force of the seed paper's Eq. (4) (Zhang et al.
2023, after Silling & Askari 2005 and Liu et al.) stops that. pdfem uses the calibration of
Silling & Askari (2005, "A meshfree method based on the peridynamic model of solid mechanics",
Computers & Structures 83, the section on short-range forces) as the force density on particle i::

    f_i = sum_j  -k_ij (r_ij - |p|) (p / |p|) V_j        for |p| < r_ij, else 0
    p = y_j - y_i,   k_i = c_S / delta_i = 15 c_i / delta_i,   c_i = 18 K_i / (pi delta_i^4)

(N/m^3; c is the bond-based micromodulus, N/m^6, so k is in N/m^7). Seed Eq. (4) is the same
linear repulsion written as c_sh (|p| / r_sh - 1); only the scaling of the constant differs.

The critical distance ``r_ij`` (Silling & Askari's d_ij, with particle radius r_i = dx_i / 2):

- same body: ``r_ij = min(0.9 |x_j - x_i|, 1.35 (r_i + r_j))`` with the reference positions x.
  In an undeformed lattice nothing acts: nearest neighbours sit at dx > 0.9 dx, the next ones at
  sqrt(2) dx > 1.35 dx.
- different bodies: there is no reference distance, so the rule is applied with the distance at
  which the two particles' cells touch, |x_j - x_i| := r_i + r_j (two lattices in contact across
  a face have their facing sites that far apart), which gives ``r_ij = 0.9 (r_i + r_j)``. Two
  bodies placed in contact therefore start force-free, exactly like two neighbours in one body,
  and the force switches on when they interpenetrate by 10 % of a spacing; the alternative
  1.35 (r_i + r_j) would push touching bodies apart across a gap of 0.35 dx.

Bodies may differ in spacing and material: the constants are per particle, and a pair uses the
harmonic mean ``k_ij = 2 k_i k_j / (k_i + k_j)`` (equal to k for equal materials; at most twice
the softer side's constant, so a stiff body does not destabilise a soft body's time step).
``k_ij`` and ``r_ij`` are symmetric and constant in time, so the force is equal and opposite
(momentum is conserved exactly, up to the rounding of V_j f_j) and conservative, with the pair
potential (J)::

    U_ij = 1/2 k_ij V_i V_j (r_ij - |p|)^2     for |p| < r_ij, else 0

(-dU_ij/dy_i = V_i f_i from this pair), reported by :meth:`ShortRangeContact.potential_energy`.
The force acts between all pairs closer than r_ij, bonded or not, as in Silling & Askari and Emu.

Search, every call over all bodies' current positions (no state kept between calls): a cell grid
of side ``h = max r_ij = 1.35 max(dx)`` (times 1 + 1e-12, so that rounding of the cell
coordinates cannot lose a pair at exactly h), over the box of the current positions, with the
particles counting-sorted by cell. Every pair is examined once, from the particle earlier in
sorted order:

- dense grid (at most ``DENSE_CELLS_PER_PARTICLE`` cells per particle, the usual case), padded
  by one empty cell: the forward half stencil of a cell is five contiguous runs of sorted
  positions (own cell after the particle and cell +z; the three cells +y; three columns +x);
- folded grid, when fragments fly apart and the box would need more cells: the longest axes are
  folded in halves (cell ix goes to bucket ix mod F) until the table has at most
  ``DENSE_CELLS_PER_PARTICLE * N`` buckets, and coordinates are clamped to 2^20 cells per axis
  (clamping and folding never separate neighbouring cells, so no pair is lost). Each particle
  scans the buckets of its 27 neighbour cells that come at or after its own, and within them
  only the particles of the cell asked for.

The scan runs in parallel (above ``SERIAL_BELOW_PARTICLES``) over contiguous chunks of sorted
positions, each chunk writing the pairs it finds into its own buffer; the buffers are then
summed serially in chunk order, i.e. in sorted-position order, so the forces are bit-identical
from run to run and for any thread or chunk count. Candidates further apart than h are rejected
with one squared distance, which is all the work an intact body costs (about 30 candidates per
particle).

One search serves every layout of the bodies (whole, or split over MPI ranks): each process
searches its owned particles and a contact halo of other ranks' particles kept with a Verlet
skin (:mod:`pdfem.forces.short_range_halo`; none on one process), in global order, on the cells
of the grid over all particles (box and dense/folded choice from the global extent and particle
count) with a table sized from the local particles: the cells of the local particles' box when
that is small, else a sparse table of the occupied buckets. The stable sort keeps the local
particles in the global sorted order, so every owned particle meets its partners in the same
order on 1 and N ranks and its force is the same bit for bit. Each pair's potential is counted
on the rank that owns the pair's first particle (in sorted order), so once over the ranks. The
kernels (cell hash, pair search, sums) are :mod:`pdfem.forces.short_range_kernels`.

Units: m, m^3, Pa, N/m^3 (force density), J.
"""

from __future__ import annotations

import math
from typing import Sequence

import numba
import numpy as np

from pdfem.forces.base import ParticleForce
from pdfem.forces.short_range_halo import ContactHalo
from pdfem.forces.short_range_kernels import (
    NO_SHIFT,
    Constants,
    Found,
    Grid,
    Table,
    add_owned,
    cells,
    counted_pairs,
    find_dense,
    find_folded,
    gather,
    sparse_table,
    sum_pairs,
)
from pdfem.geometry.cell_hash import bounding_box, counting_sort
from pdfem.parallel.kernels import SERIAL_BELOW_PARTICLES

__all__ = ["ShortRangeContact", "short_range_constant", "DENSE_CELLS_PER_PARTICLE"]

#: number the cells densely while the grid has at most this many cells per particle, else fold
DENSE_CELLS_PER_PARTICLE = 4
#: cell coordinates are clamped to [0, _AXIS_CELLS) per axis (keys pack 21 bits per axis)
_AXIS_CELLS = 1 << 20
_INITIAL_CAPACITY = 1024  # pair slots per chunk before the first growth


def short_range_constant(K: float, delta: float, factor: float = 15.0) -> float:
    """Silling & Askari's short-range constant per unit length, k = factor * c / delta (N/m^7):
    ``factor * 18 K / (pi delta^4) / delta`` for the bulk modulus ``K`` (Pa) and the horizon
    ``delta`` (m), with 18 K / (pi delta^4) the bond-based micromodulus c (N/m^6) and ``factor``
    = c_S / c (Silling & Askari 2005: 15)."""
    return factor * 18.0 * float(K) / (math.pi * float(delta) ** 5)



class ShortRangeContact(ParticleForce):
    """Short-range repulsion among the particles of one or more ice bodies.

    Parameters
    ----------
    bodies
        The ice bodies (:class:`pdfem.pd.body.IceBody`: ``y``, ``x0``, ``vol``, ``dx``,
        ``delta``, ``material.K``, ``f``, ``layout``); a single body may be passed alone. Every
        call is collective when they are split over ranks; forces go to the owned particles.
    stiffness_factor
        c_S / c, the short-range constant over the bond-based micromodulus (Silling & Askari: 15).
    distance_factor
        Fraction of the reference distance at which the force starts (Silling & Askari: 0.9).
    radius_factor
        Cap of the critical distance in particle radii dx / 2 (Silling & Askari: 1.35).
    n_chunks
        Chunks of the parallel scan (default: 4 per numba thread). The forces do not depend on it.

    Attributes
    ----------
    n_active
        Number of interacting pairs found by the last call that this process counts (those
        whose first particle it owns; :meth:`total_pairs` sums over ranks).
    cell_size
        Side of the search cells, m (the largest critical distance).
    dense, n_buckets
        Whether the last search used the dense grid (else the folded one), and its number of
        buckets (at most ``DENSE_CELLS_PER_PARTICLE * max(N, 1024)``).
    halo
        The :class:`~pdfem.forces.short_range_halo.ContactHalo`: this process's owned particles
        and ghosts.
    """

    def __init__(self, bodies: "Sequence", *, stiffness_factor: float = 15.0,
                 distance_factor: float = 0.9, radius_factor: float = 1.35,
                 n_chunks: int | None = None):
        if not isinstance(bodies, (list, tuple)):
            bodies = [bodies]
        if len(bodies) == 0:
            raise ValueError("short-range contact needs at least one ice body")
        for name, v in (("stiffness_factor", stiffness_factor),
                        ("distance_factor", distance_factor), ("radius_factor", radius_factor)):
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"{name} must be a positive finite number, got {v!r}")
        self.bodies: list = list(bodies)
        # the particles of all bodies, numbered body after body (whole bodies)
        sizes = [int(b.n_global) for b in self.bodies]
        self.offsets = np.concatenate(([0], np.cumsum(sizes))).astype(np.int64)
        n = int(self.offsets[-1])
        if n >= 2 ** 31 - 1:
            raise ValueError(f"at most 2**31 - 2 particles in short-range contact, got {n}")
        self.n = n
        self.distance_factor = float(distance_factor)
        self.radius_factor = float(radius_factor)
        k_body = [short_range_constant(b.material.K, b.delta, stiffness_factor)
                  for b in self.bodies]
        r_body = [0.5 * float(b.dx) for b in self.bodies]
        dx_max = max(float(b.dx) for b in self.bodies)
        # a margin of 1e-12 keeps pairs at a critical distance of exactly h from being lost to
        # the rounding of the cell coordinates
        self.cell_size = max(self.radius_factor, self.distance_factor) * dx_max * (1.0 + 1e-12)
        threads = int(numba.get_num_threads())
        self._chunks_wanted = max(1, 4 * threads if n_chunks is None else int(n_chunks))
        self.comm = self.bodies[0].layout.comm
        self.halo = ContactHalo(self.bodies, self.offsets, k_body, r_body, self.cell_size,
                                self.comm)
        self._size = -1
        self._no_ub = np.empty(0, dtype=np.int64)
        self._start = np.empty(1, dtype=np.int64)
        self._n_touched = 0
        self.n_active = 0
        self.dense = True
        self.n_buckets = 0
        self.grid_buckets = 0  # buckets of the grid over all particles (not allocated here)
        self._cap = _INITIAL_CAPACITY
        self._pair = np.empty((self._chunks_wanted * self._cap, 2), dtype=np.int32)
        self._val = np.empty((self._chunks_wanted * self._cap, 4))
        self._counts = np.zeros(1, dtype=np.int64)
        self._reserve(0)

    label = "short-range contact"
    energy_key = "short_range_potential"
    """Key of :meth:`potential_energy` in the energy history (:class:`ParticleForce`)."""

    # -- search ---------------------------------------------------------------------------------
    def _reserve(self, n: int) -> None:
        """Per-particle work arrays for at least ``n`` particles (grown by a quarter at least)."""
        if n <= self._size:
            return
        if self._size >= 0:
            n = max(n, self._size + self._size // 4)
        self._size = n
        self._ijk = np.empty((n, 3), dtype=np.int64)
        self._key = np.empty(n, dtype=np.int64)
        self._bucket = np.empty(n, dtype=np.int64)
        self._perm = np.empty(n, dtype=np.int32)
        self._ys = np.empty((n, 3))
        self._ijks = np.empty((n, 3), dtype=np.int64)
        self._keys = np.empty(n, dtype=np.int64)
        self._buckets = np.empty(n, dtype=np.int64)
        self._acc = np.zeros((n, 3))
        self._mark = np.zeros(n, dtype=np.uint8)
        self._touched = np.empty(n, dtype=np.int32)
        self._ub = np.empty(n, dtype=np.int64)
        self._sstart = np.empty(n + 1, dtype=np.int64)

    @staticmethod
    def budget(n: int) -> int:
        """Most cells (buckets) of a table for ``n`` particles."""
        return DENSE_CELLS_PER_PARTICLE * max(n, 1024)

    def _grid(self, lo, hi, n_total: int):
        """Cell geometry over the box [lo, hi] for ``n_total`` particles: dims, pad, fold and
        the number of buckets (sets ``dense``)."""
        inv_h = 1.0 / self.cell_size
        dims = np.array([min(int((hi[k] - lo[k]) * inv_h) + 1, _AXIS_CELLS) for k in range(3)],
                        dtype=np.int64)
        budget = self.budget(n_total)
        self.dense = float(np.prod(dims + 2)) <= budget
        if self.dense:  # one empty cell around the grid: the stencil needs no bounds checks
            pad = 1
            fold = dims + 2
        else:  # fold the longest axes in halves until the table fits the budget
            pad = 0
            fold = dims.copy()
            while float(np.prod(fold)) > budget:
                k = int(np.argmax(fold))
                fold[k] = (fold[k] + 1) // 2
        return dims, pad, fold, int(np.prod(fold))

    def _local_table(self, y, glo, dims, fold, nb, m: int):
        """The table of the local particles: the cells of their box on the global grid when
        that is small (a shifted dense table), else a sparse table of the occupied buckets;
        returns (shift, sparse, fold, buckets)."""
        if not self.dense:
            return NO_SHIFT, True, fold, nb
        llo, lhi, _ = bounding_box(y)
        inv_h = 1.0 / self.cell_size
        first = np.array([int(min((llo[k] - glo[k]) * inv_h, float(dims[k] - 1)))
                          for k in range(3)], dtype=np.int64)
        last = np.array([int(min((lhi[k] - glo[k]) * inv_h, float(dims[k] - 1)))
                         for k in range(3)], dtype=np.int64)
        box = last - first + 3
        if float(np.prod(box)) <= self.budget(m):
            return first, False, box, int(np.prod(box))
        return NO_SHIFT, True, fold, nb

    def _scan(self, y, lo, dims, pad, fold, nb, chunk_ptr, counts, shift, sparse):
        """Sort the local particles ``y`` into the grid and find the interacting pairs into
        ``self._pair``, ``self._val``, ``counts`` (per chunk). ``sparse``: a stable sort and a
        table of the occupied buckets only (else a counting sort into all ``nb`` buckets)."""
        h, n = self.halo, y.shape[0]
        ijk, key, bucket, perm = self._ijk[:n], self._key[:n], self._bucket[:n], self._perm[:n]
        ys, ijks, keys, buckets = self._ys[:n], self._ijks[:n], self._keys[:n], self._buckets[:n]
        cells(y, lo, 1.0 / self.cell_size, dims, pad, fold, ijk, key, bucket, shift)
        if sparse:
            perm[:] = np.argsort(bucket, kind="stable")
            k = sparse_table(bucket[perm], self._ub, self._sstart)
            start, ub = self._sstart[:k + 1], self._ub[:k]
        else:
            if self._start.shape[0] != nb + 1:
                self._start = np.empty(nb + 1, dtype=np.int64)
            counting_sort(bucket, nb, self._start, perm)
            start, ub = self._start, self._no_ub
        gather(perm, y, ijk, key, bucket, ys, ijks, keys, buckets, not self.dense)
        n_chunks = chunk_ptr.shape[0] - 1
        if self._pair.shape[0] < n_chunks * self._cap:
            self._pair = np.empty((n_chunks * self._cap, 2), dtype=np.int32)
            self._val = np.empty((n_chunks * self._cap, 4))
        table = Table(ys, ijks, keys, buckets, start, ub, perm)
        consts = Constants(h.x0, h.vol, h.stiffness, h.radius, h.body)
        grid = Grid(self.cell_size, dims, fold, self.distance_factor, self.radius_factor)
        while True:
            par = n >= SERIAL_BELOW_PARTICLES
            found = Found(chunk_ptr, self._cap, self._pair, self._val, counts)
            if self.dense:
                find_dense(par, table, consts, grid, found)
            else:
                find_folded(par, table, consts, grid, found)
            most = int(counts.max())
            if most <= self._cap:
                break
            self._cap = 2 * most
            self._pair = np.empty((n_chunks * self._cap, 2), dtype=np.int32)
            self._val = np.empty((n_chunks * self._cap, 4))

    def _search(self) -> float:
        """Find the pairs of the local particles at the current positions; returns the
        potential (J) of the pairs this process counts. Collective."""
        h = self.halo
        self._n_touched = 0
        self.n_active = 0
        if self.n < 2:
            return 0.0
        glo, ghi = h.update()
        m = h.m
        dims, pad, fold, nb = self._grid(glo, ghi, self.n)  # the grid over all particles
        self.grid_buckets = nb
        if m < 2:
            return 0.0
        self._reserve(m)
        shift, sparse, fold, nb = self._local_table(h.y, glo, dims, fold, nb, m)
        self.n_buckets = m if sparse else nb
        n_chunks = max(1, min(self._chunks_wanted, m))
        chunk_ptr = (np.arange(n_chunks + 1, dtype=np.int64) * m) // n_chunks
        counts = np.zeros(n_chunks, dtype=np.int64)
        self._scan(h.y, glo, dims, pad, fold, nb, chunk_ptr, counts, shift, sparse)
        self._counts = counts
        n_pairs, energy = counted_pairs(counts, self._cap, self._pair, self._val, h.owned)
        self.n_active = int(n_pairs)
        if counts.sum():
            self._n_touched, _ = sum_pairs(counts, self._cap, self._pair, self._val, h.vol,
                                           self._acc, self._mark, self._touched)
        return float(energy)

    def _add_into(self, fs: list) -> None:
        """Add the last search's force density of each owned particle into ``fs`` (one local
        array per body)."""
        h, nt = self.halo, self._n_touched
        if nt == 0:
            return
        k = 0
        for f, o in zip(fs, h.own):
            add_owned(f, o, h.own_pos[k:k + len(o)], self._acc, self._touched, nt, self._mark)
            k += len(o)

    # -- public ---------------------------------------------------------------------------------
    def add_forces(self) -> int:
        """Add the short-range force density (N/m^3) at the current positions into each body's f.

        Call after the bodies' peridynamic forces were computed at the same positions.

        Returns
        -------
        int
            The number of interacting pairs this process counts.

        Raises
        ------
        FloatingPointError
            If a position is NaN or infinite.
        """
        self._search()
        self._add_into([b.f for b in self.bodies])
        return self.n_active

    def forces(self) -> list[np.ndarray]:
        """The short-range force density (N/m^3) on each body's local particles at the current
        positions (zero on halo particles).

        Returns
        -------
        list of ndarray
            One (n_b, 3) array per body; the bodies' ``f`` are not touched.
        """
        self._search()
        out = [np.zeros((b.x0.shape[0], 3)) for b in self.bodies]
        self._add_into(out)
        return out

    def potential_energy(self) -> float:
        """Potential energy of the short-range force at the current positions, J.

        ``sum over interacting pairs of 1/2 k_ij V_i V_j (r_ij - |y_j - y_i|)^2`` (over all
        ranks: collective).
        """
        return float(self.comm.allreduce_sum(self._search()))

    def total_pairs(self) -> int:
        """Interacting pairs found by the last call, over all ranks (collective)."""
        return int(self.comm.allreduce_sum(np.int64(self.n_active)))

    def invalidate(self) -> None:
        """Rebuild the contact halo at the next call (e.g. after particles moved between
        ranks; a change of a body's layout is also noticed by itself)."""
        self.halo.invalidate()
