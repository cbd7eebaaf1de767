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

Verlet pair list. Each process evaluates the force from a list of candidate pairs that it
builds only when its contact halo (:mod:`pdfem.forces.short_range_halo`: its owned particles
and the other ranks' particles near them, none on one process) is refreshed: at the first call,
then when some particle, on any rank, has moved more than s/2 from where it was at the last
refresh, or when the owned set changed or :meth:`ShortRangeContact.invalidate` was called. The
skin is the halo's, ``s = 0.3 h``, with the cut-off ``h = max r_ij = 1.35 max(dx)`` (times
1 + 1e-12). A pair is a candidate when ``|p| < r_ij + s`` at the build (its own r_ij; s
enlarged by a relative 1e-6 against rounding). Why that is enough: until the next build no
particle is more than s/2 from its position at the build, so a pair's distance changes by at
most s, and every pair with ``|p| < r_ij`` now was a candidate; its partner is local, since the
halo holds every particle within h + s of the rank's owned ones at the refresh.

The build: a cell grid of side h + s over the box of the local particles, the particles
counting-sorted by cell, every pair examined once, from the particle earlier in sorted order
(:mod:`pdfem.forces.short_range_kernels`):

- dense grid (at most ``DENSE_CELLS_PER_PARTICLE`` cells per particle, the usual case), padded
  by one empty cell: the forward half stencil of a cell is five contiguous runs of sorted
  positions (own cell after the particle and cell +z; the three cells +y; three columns +x);
- folded grid, when fragments fly apart and the box would need more cells: the longest axes are
  folded in halves (cell ix goes to bucket ix mod F) until the table has at most
  ``DENSE_CELLS_PER_PARTICLE * max(m, 1024)`` buckets (m local particles), and coordinates are
  clamped to 2^20 cells per axis (clamping and folding never separate neighbouring cells, so no
  pair is lost). Each particle scans the buckets of its 27 neighbour cells that come at or
  after its own, and within them only the particles of the cell asked for.

The scan runs in parallel (above ``SERIAL_BELOW_PARTICLES``) over chunks of sorted positions,
each into its own buffer. A candidate's constants, r_ij and k_ij V_i V_j, are computed once,
from the side of its lower-numbered particle, and stored with it. The list is a CSR over the
local particles (:mod:`pdfem.forces.short_range_list_kernels`): row i holds every partner of
an owned particle i (both directions of each pair), ascending by local index, which is the
global particle order (body offset + index in the body), since the halo keeps its arrays in
that order on every rank.

Per step, a pass over the list finds the particles in contact: each pair's distance tested
once, from its lower-numbered end, and a whole row skipped while the smallest margin
``|p| - r_ij`` of its pairs at the build exceeds twice the largest move of any particle since
(none of them can have closed it; a quiet sheet's rows all are). Then a ``prange`` over the
owned particles in a contact: each particle sums
its own force from its interacting partners in row order and skips the other candidates
entirely. Its force is therefore a function of the current positions alone: the same bit for
bit whenever the list was built (a list built long ago only holds more candidates, which add
nothing), for any thread count and on 1 and N ranks; so a run restarted from a checkpoint,
whose list is built afresh at its first call, continues bit for bit. Pair i-j evaluated from
j's row gives exactly the negated force (p negated exactly, the same distance and stored
constants). A pair's potential and count go to the rank that owns its lower-numbered
particle, once over the ranks, summed per particle in global order. A call that finds every
position, on every rank, bit for bit where the last pass left it (the forces again after bonds
broke in a step, the energy rows) takes that pass's forces and tallies instead of a new one.

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
    Constants,
    Found,
    Grid,
    Table,
    cells,
    find_dense,
    find_folded,
    gather,
)
from pdfem.forces.short_range_list_kernels import (add_owned, contacts_near, pair_forces,
                                                  pair_rows, row_margins, tally)
from pdfem.geometry.cell_hash import bounding_box, counting_sort
from pdfem.parallel.kernels import SERIAL_BELOW_PARTICLES

__all__ = ["ShortRangeContact", "short_range_constant", "DENSE_CELLS_PER_PARTICLE"]

#: number the cells densely while the grid has at most this many cells per particle, else fold
DENSE_CELLS_PER_PARTICLE = 4
#: cell coordinates are clamped to [0, _AXIS_CELLS) per axis (keys pack 21 bits per axis)
_AXIS_CELLS = 1 << 20
_INITIAL_CAPACITY = 1024  # candidate slots per chunk before the first growth
#: the list's skin over the halo's: a relative 1e-6 more, so that the rounding of distances
#: cannot lose a pair that the halo's drift rule lets come into range
_SKIN_MARGIN = 1.0 + 1e-6
#: a row of the list is skipped while its pairs' margins at the build exceed twice the largest
#: move since plus this fraction of the cut-off (the rounding of the distances is ~1e-16 of it)
MARGIN_ROUNDING = 1e-9


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
        Chunks of the parallel candidate search (default: 4 per numba thread). Neither the
        list's contents nor the forces depend on it.

    Attributes
    ----------
    passes
        Force passes over the list so far (a call at the positions of the last pass, bit for
        bit, takes that pass's results instead).
    n_active
        Number of interacting pairs at the last call that this process counts (those whose
        lower-numbered particle it owns; :meth:`total_pairs` sums over ranks).
    cell_size
        The cut-off h, m: the largest critical distance (the list's cells are h + s).
    skin
        The pair list's Verlet skin s, m (the contact halo's).
    builds
        How many times this process has built the pair list (once per refresh of the halo).
    dense, n_buckets
        Whether the last build used the dense grid (else the folded one), and its number of
        buckets (at most ``DENSE_CELLS_PER_PARTICLE * max(m, 1024)`` for m local particles).
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
        self.skin = self.halo.skin * _SKIN_MARGIN
        self._side = (self.cell_size + self.skin) * (1.0 + 1e-12)  # the list's cell side
        self.builds = 0
        self._built = -1  # the halo's refresh count at the last build
        self._evaluated = -1  # the list (its build) of the last force pass
        self.passes = 0  # force passes over the list so far
        self._n_active, self._energy = 0, 0.0  # that pass's pairs and potential (J)
        self.n_active = 0
        self.dense = True
        self.n_buckets = 0
        self._size = -1
        self._start = np.empty(1, dtype=np.int64)
        self._cap = _INITIAL_CAPACITY  # candidate slots per chunk of the search (grows)
        # the list: owned rows, CSR of partners with the pairs' r_ij and k_ij V_i V_j
        self._rows = np.empty(0, dtype=np.int64)
        self._row_ptr = np.zeros(1, dtype=np.int64)
        self._split = np.zeros(1, dtype=np.int64)
        self._nbr = np.empty(0, dtype=np.int32)
        self._crit = np.empty(0)
        self._kvv = np.empty(0)
        self._reserve(0)

    label = "short-range contact"
    energy_key = "short_range_potential"
    """Key of :meth:`potential_energy` in the energy history (:class:`ParticleForce`)."""

    # -- the pair list ----------------------------------------------------------------------------
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
        self._hit = np.zeros(n, dtype=np.uint8)
        self._near = np.zeros(n, dtype=np.uint8)
        self._n_up = np.zeros(n, dtype=np.int64)
        self._e_up = np.zeros(n)

    @staticmethod
    def budget(n: int) -> int:
        """Most cells (buckets) of a table for ``n`` particles."""
        return DENSE_CELLS_PER_PARTICLE * max(n, 1024)

    def _grid(self, lo, hi, n: int):
        """Cell geometry of side h + s over the box [lo, hi] of ``n`` particles: dims, pad,
        fold and the number of buckets (sets ``dense`` and ``n_buckets``)."""
        inv_h = 1.0 / self._side
        dims = np.array([min(int((hi[k] - lo[k]) * inv_h) + 1, _AXIS_CELLS) for k in range(3)],
                        dtype=np.int64)
        budget = self.budget(n)
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
        self.n_buckets = int(np.prod(fold))
        return dims, pad, fold, self.n_buckets

    def _find(self, y) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The candidate pairs of the local particles at ``y``: their count per chunk and the
        buffers ``pair``, ``val`` of :class:`Found` (chunk c in slots ``[c cap, (c+1) cap)``)."""
        h, n = self.halo, y.shape[0]
        lo, hi, _ = bounding_box(y) if n else (np.zeros(3), np.zeros(3), True)
        dims, pad, fold, nb = self._grid(lo, hi, n)
        ijk, key, bucket, perm = self._ijk[:n], self._key[:n], self._bucket[:n], self._perm[:n]
        ys, ijks, keys, buckets = self._ys[:n], self._ijks[:n], self._keys[:n], self._buckets[:n]
        cells(y, lo, 1.0 / self._side, dims, pad, fold, ijk, key, bucket)
        if self._start.shape[0] != nb + 1:
            self._start = np.empty(nb + 1, dtype=np.int64)
        counting_sort(bucket, nb, self._start, perm)
        gather(perm, y, ijk, key, bucket, ys, ijks, keys, buckets, not self.dense)
        n_chunks = max(1, min(self._chunks_wanted, n))
        chunk_ptr = (np.arange(n_chunks + 1, dtype=np.int64) * n) // n_chunks
        counts = np.zeros(n_chunks, dtype=np.int64)
        table = Table(ys, ijks, keys, buckets, self._start, perm)
        consts = Constants(h.x0, h.vol, h.stiffness, h.radius, h.body)
        grid = Grid(self._side, dims, fold, self.distance_factor, self.radius_factor, self.skin)
        par = n >= SERIAL_BELOW_PARTICLES
        while True:
            pair = np.empty((n_chunks * self._cap, 2), dtype=np.int32)
            val = np.empty((n_chunks * self._cap, 2))
            found = Found(chunk_ptr, self._cap, pair, val, counts)
            (find_dense if self.dense else find_folded)(par, table, consts, grid, found)
            most = int(counts.max())
            if most <= self._cap:
                return counts, pair, val
            self._cap = 2 * most

    def _build(self) -> None:
        """The pair list of the local particles at their current positions (those of the
        halo's last refresh)."""
        h, m = self.halo, self.halo.m
        self._built = h.refreshes
        self.builds += 1
        self._reserve(m)
        self._rows = np.flatnonzero(h.owned).astype(np.int64)
        counts, pair, val = self._find(h.y)
        entries = 2 * int(counts.sum())
        if self._nbr.shape[0] < entries:
            size = max(entries, self._nbr.shape[0] + self._nbr.shape[0] // 4)
            self._nbr = np.empty(size, dtype=np.int32)
            self._crit = np.empty(size)
            self._kvv = np.empty(size)
        self._row_ptr = np.empty(m + 1, dtype=np.int64)
        self._split = np.empty(m + 1, dtype=np.int64)
        pair_rows(counts, self._cap, pair, val, h.owned, self._row_ptr, self._nbr, self._crit,
                  self._kvv, self._split)
        self._margin = np.full(m, np.inf)
        row_margins(self._rows, self._row_ptr, self._split, self._nbr, self._crit, h.y, h.owned,
                    self._margin)
        self._margins = np.sort(self._margin[self._rows])  # how many rows a reach tests

    def _evaluate(self) -> float:
        """The forces at the current positions (rebuilding the list when the halo was
        refreshed); returns the potential (J) of the pairs this process counts. Collective."""
        self.n_active = 0
        if self.n < 2:
            return 0.0
        h = self.halo
        h.update()
        if h.refreshes != self._built:
            self._build()
        elif not h.moved and self._evaluated == self._built:
            # the positions of the last pass, bit for bit (a step's forces again after bonds
            # broke, an energy row): its forces and tallies stand
            self.n_active = self._n_active
            return self._energy
        rows = self._rows
        self.passes += 1
        near = self._near[:h.m]
        # rows whose pairs were all farther apart at the build than twice the largest move
        # since are skipped (the allowance covers the round-off of the distances, ~1e-16 h);
        # the passes thread when many rows are tested
        reach = 2.0 * h.largest_move + MARGIN_ROUNDING * self.cell_size
        par = int(np.searchsorted(self._margins, reach, side="right")) >= SERIAL_BELOW_PARTICLES
        contacts_near(par, rows, self._row_ptr, self._split, self._nbr, self._crit, h.y, h.owned,
                      self._margin, reach, near)
        pair_forces(par, rows, self._row_ptr, self._nbr, self._crit, self._kvv, h.y, h.vol, near,
                    self._acc, self._hit, self._n_up, self._e_up)
        n_pairs, energy = tally(rows, self._hit, self._n_up, self._e_up)
        self.n_active = self._n_active = int(n_pairs)
        self._energy = float(energy)
        self._evaluated = self._built
        return self._energy

    def _add_into(self, fs: list) -> None:
        """Add the last evaluation's force density of each owned particle into ``fs`` (one
        local array per body)."""
        h = self.halo
        if self._built < 0:
            return
        k = 0
        for f, o in zip(fs, h.own):
            add_owned(f, o, h.own_pos[k:k + len(o)], self._acc, self._hit)
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
        self._evaluate()
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
        self._evaluate()
        out = [np.zeros((b.x0.shape[0], 3)) for b in self.bodies]
        self._add_into(out)
        return out

    def potential_energy(self) -> float:
        """Potential energy of the short-range force at the current positions, J.

        ``sum over interacting pairs of 1/2 k_ij V_i V_j (r_ij - |y_j - y_i|)^2`` (over all
        ranks: collective).
        """
        return float(self.comm.allreduce_sum(self._evaluate()))

    def total_pairs(self) -> int:
        """Interacting pairs found by the last call, over all ranks (collective)."""
        return int(self.comm.allreduce_sum(np.int64(self.n_active)))

    def invalidate(self) -> None:
        """Rebuild the contact halo and the pair list at the next call (e.g. after particles
        moved between ranks; a change of a body's layout is also noticed by itself)."""
        self.halo.invalidate()
