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

Bodies split over MPI ranks (:class:`pdfem.pd.distributed.DistributedIce`, which carry the
communicator) are searched by :class:`_DistributedSearch`: each rank takes the particles of
other ranks within 1.5 h of the box of its own particles (fragments move, so these partners
change every step; the static bond halo is not used), orders its own particles and these
ghosts by global index (body offset + index in the body, the serial order) and runs the
serial kernels above on them, on the grid the serial run would use (box and dense/folded
choice from the global extent and particle count; a dense grid is cut down to the cells of the
local particles, which keeps their order, so a rank's table scales with its own particles). The stable counting sort keeps the local
particles in the serial sorted order, so every owned particle meets its partners in the
serial order and its force is the serial one bit for bit; each pair's potential is counted on
the rank that owns the pair's first particle, and the sums are over ranks.

Units: m, m^3, Pa, N/m^3 (force density), J.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Sequence

import numba
import numpy as np
from numba import prange

from pdfem.forces.base import ParticleForce
from pdfem.pd.workspace import SERIAL_BELOW_PARTICLES, twin

if TYPE_CHECKING:
    from pdfem.pd.body import IceBody

__all__ = ["ShortRangeContact", "short_range_constant", "DENSE_CELLS_PER_PARTICLE"]

#: number the cells densely while the grid has at most this many cells per particle, else fold
DENSE_CELLS_PER_PARTICLE = 4
#: cell coordinates are clamped to [0, _AXIS_CELLS) per axis (keys pack 21 bits per axis)
_AXIS_CELLS = 1 << 20
_INITIAL_CAPACITY = 1024  # pair slots per chunk before the first growth
_NO_SHIFT = np.zeros(3, dtype=np.int64)
_NOT_FINITE = ("ice particle positions are not finite (NaN or Inf): the run has become "
               "unstable")


def short_range_constant(K: float, delta: float, factor: float = 15.0) -> float:
    """Silling & Askari's short-range constant per unit length, k = factor * c / delta (N/m^7).

    Parameters
    ----------
    K
        Bulk modulus (Pa).
    delta
        Horizon (m).
    factor
        c_S / c; Silling & Askari (2005) use 15.

    Returns
    -------
    float
        ``factor * 18 K / (pi delta^4) / delta``, with 18 K / (pi delta^4) the bond-based
        micromodulus c (N/m^6).
    """
    return factor * 18.0 * float(K) / (math.pi * float(delta) ** 5)


# --------------------------------------------------------------------------------------------
# kernels


@numba.njit(cache=True)
def _extent(y):
    """Per-axis min and max of y, and whether every entry is finite (N >= 1)."""
    lo = np.empty(3)
    hi = np.empty(3)
    finite = True
    for k in range(3):
        lo[k] = y[0, k]
        hi[k] = y[0, k]
    for i in range(y.shape[0]):
        for k in range(3):
            v = y[i, k]
            if not math.isfinite(v):
                finite = False
            if v < lo[k]:
                lo[k] = v
            if v > hi[k]:
                hi[k] = v
    return lo, hi, finite


@numba.njit(cache=True, inline="always")
def _bucket(ix, iy, iz, fold):
    """Bucket of cell (ix, iy, iz): its linear index in the grid folded to ``fold`` cells."""
    if ix >= fold[0]:
        ix %= fold[0]
    if iy >= fold[1]:
        iy %= fold[1]
    if iz >= fold[2]:
        iz %= fold[2]
    return (ix * fold[1] + iy) * fold[2] + iz


@numba.njit(cache=True)
def _cells(y, lo, inv_h, dims, pad, fold, ijk, key, bucket, shift):
    """Clamped (and padded) cell coordinates, packed cell key and bucket of every particle;
    the grid's cells start at cell ``shift`` (zeros: at ``lo``)."""
    top_x = float(dims[0] - 1)
    top_y = float(dims[1] - 1)
    top_z = float(dims[2] - 1)
    for i in range(y.shape[0]):
        # y >= lo, so the scaled offset is >= 0 and int() floors it; clamp before converting
        cx = int(min((y[i, 0] - lo[0]) * inv_h, top_x)) - shift[0] + pad
        cy = int(min((y[i, 1] - lo[1]) * inv_h, top_y)) - shift[1] + pad
        cz = int(min((y[i, 2] - lo[2]) * inv_h, top_z)) - shift[2] + pad
        ijk[i, 0] = cx
        ijk[i, 1] = cy
        ijk[i, 2] = cz
        key[i] = (cx << 42) | (cy << 21) | cz
        bucket[i] = _bucket(cx, cy, cz, fold)


@numba.njit(cache=True)
def _sort(bucket, nb, start, perm):
    """Stable counting sort by bucket: ``start`` (nb+1,) bucket offsets and ``perm``."""
    start[:] = 0
    for i in range(bucket.shape[0]):
        start[bucket[i] + 1] += 1
    for b in range(nb):
        start[b + 1] += start[b]
    for i in range(bucket.shape[0]):
        b = bucket[i]
        perm[start[b]] = i
        start[b] += 1
    for b in range(nb, 0, -1):
        start[b] = start[b - 1]
    start[0] = 0


@numba.njit(cache=True)
def _gather(perm, y, ijk, key, bucket, ys, ijks, keys, buckets, all_fields):
    for s in range(perm.shape[0]):
        i = perm[s]
        ys[s, 0] = y[i, 0]
        ys[s, 1] = y[i, 1]
        ys[s, 2] = y[i, 2]
        buckets[s] = bucket[i]
        if all_fields:
            ijks[s, 0] = ijk[i, 0]
            ijks[s, 1] = ijk[i, 1]
            ijks[s, 2] = ijk[i, 2]
            keys[s] = key[i]


@numba.njit(cache=True, inline="always")
def _interact(i, j, px, py, pz, d2, x0, vol, stiff, rad, body, dist_factor, rad_factor, store,
              slot, pair, val):
    """Whether particles i, j (p = y_j - y_i, d2 = |p|^2) interact; if so and ``store``, write
    the pair, its force on i (N) and its potential (J) into ``slot``."""
    rsum = rad[i] + rad[j]
    if body[i] == body[j]:
        ex = x0[j, 0] - x0[i, 0]
        ey = x0[j, 1] - x0[i, 1]
        ez = x0[j, 2] - x0[i, 2]
        r = min(dist_factor * math.sqrt(ex * ex + ey * ey + ez * ez), rad_factor * rsum)
    else:
        r = dist_factor * rsum
    if d2 >= r * r:
        return False
    if store:
        d = math.sqrt(d2)
        k = 2.0 * stiff[i] * stiff[j] / (stiff[i] + stiff[j]) * vol[i] * vol[j]
        s = -k * (r - d) / d  # force on i (N) = s p
        pair[slot, 0] = i
        pair[slot, 1] = j
        val[slot, 0] = s * px
        val[slot, 1] = s * py
        val[slot, 2] = s * pz
        val[slot, 3] = 0.5 * k * (r - d) * (r - d)
    return True


@twin(fastmath=False)
def _find_dense(ys, buckets, start, perm, x0, vol, stiff, rad, body, h, fold, dist_factor,
                rad_factor, chunk_ptr, cap, pair, val, counts):
    """Pairs on a dense grid padded by one empty cell on every side, per chunk of sorted
    positions, into the chunk's slots ``[c*cap, (c+1)*cap)``.

    The forward half stencil of a particle's cell is five contiguous runs of sorted positions:
    the own cell after the particle and the cell +z; the three cells +y; and the three columns
    of three cells +x. The runs' bounds are looked up once per cell.
    """
    h2 = h * h
    nz = fold[2]
    nyz = fold[1] * fold[2]
    C = chunk_ptr.shape[0] - 1
    for c in prange(C):
        run_lo = np.empty(5, dtype=np.int64)
        run_hi = np.empty(5, dtype=np.int64)
        last = -1
        cnt = 0
        base = c * cap
        for a in range(chunk_ptr[c], chunk_ptr[c + 1]):
            ba = buckets[a]
            if ba != last:  # a new cell
                last = ba
                run_hi[0] = start[ba + 2]
                for run in range(1, 5):
                    b = ba + nz if run == 1 else ba + nyz + (run - 3) * nz
                    run_lo[run] = start[b - 1]
                    run_hi[run] = start[b + 2]
            run_lo[0] = a + 1
            yax = ys[a, 0]
            yay = ys[a, 1]
            yaz = ys[a, 2]
            for run in range(5):
                for q in range(run_lo[run], run_hi[run]):
                    px = ys[q, 0] - yax
                    py = ys[q, 1] - yay
                    pz = ys[q, 2] - yaz
                    d2 = px * px + py * py + pz * pz
                    if d2 >= h2:
                        continue
                    if _interact(perm[a], perm[q], px, py, pz, d2, x0, vol, stiff, rad, body,
                                 dist_factor, rad_factor, cnt < cap, base + cnt, pair, val):
                        cnt += 1
        counts[c] = cnt


@twin(fastmath=False)
def _find_folded(ys, ijks, keys, buckets, start, perm, x0, vol, stiff, rad, body, h, dims, fold,
                 dist_factor, rad_factor, chunk_ptr, cap, pair, val, counts):
    """:func:`_find_dense` for a folded grid: buckets hold several cells, told apart by key.

    Each particle scans the buckets of its 27 neighbour cells that come at or after its own
    bucket, from the sorted position after its own on, and only the particles of the cell asked
    for, so each pair is seen once, from the particle earlier in sorted order."""
    h2 = h * h
    C = chunk_ptr.shape[0] - 1
    for c in prange(C):
        nb_bucket = np.empty(27, dtype=np.int64)
        nb_key = np.empty(27, dtype=np.int64)
        n_nb = 0
        last_key = np.int64(-1)
        cnt = 0
        base = c * cap
        for a in range(chunk_ptr[c], chunk_ptr[c + 1]):
            ka = keys[a]
            ba = buckets[a]
            if ka != last_key:  # the stencil of a new cell
                last_key = ka
                n_nb = 0
                for ox in range(-1, 2):
                    ix = ijks[a, 0] + ox
                    if ix < 0 or ix >= dims[0]:
                        continue
                    for oy in range(-1, 2):
                        iy = ijks[a, 1] + oy
                        if iy < 0 or iy >= dims[1]:
                            continue
                        for oz in range(-1, 2):
                            iz = ijks[a, 2] + oz
                            if iz < 0 or iz >= dims[2]:
                                continue
                            b = _bucket(ix, iy, iz, fold)
                            if b < ba:
                                continue
                            nb_bucket[n_nb] = b
                            nb_key[n_nb] = (ix << 42) | (iy << 21) | iz
                            n_nb += 1
            yax = ys[a, 0]
            yay = ys[a, 1]
            yaz = ys[a, 2]
            for t in range(n_nb):
                b = nb_bucket[t]
                kb = nb_key[t]
                q0 = start[b]
                if b == ba:
                    q0 = a + 1
                for q in range(q0, start[b + 1]):
                    if keys[q] != kb:
                        continue
                    px = ys[q, 0] - yax
                    py = ys[q, 1] - yay
                    pz = ys[q, 2] - yaz
                    d2 = px * px + py * py + pz * pz
                    if d2 >= h2:
                        continue
                    if _interact(perm[a], perm[q], px, py, pz, d2, x0, vol, stiff, rad, body,
                                 dist_factor, rad_factor, cnt < cap, base + cnt, pair, val):
                        cnt += 1
        counts[c] = cnt


@numba.njit(cache=True)
def _sum_pairs(counts, cap, pair, val, vol, acc, mark, touched):
    """Force density per touched particle into ``acc`` (chunk order); returns (touched, U)."""
    nt = 0
    energy = 0.0
    for c in range(counts.shape[0]):
        for t in range(c * cap, c * cap + counts[c]):
            for e in range(2):
                g = pair[t, e]
                if mark[g] == 0:
                    mark[g] = 1
                    acc[g, 0] = 0.0
                    acc[g, 1] = 0.0
                    acc[g, 2] = 0.0
                    touched[nt] = g
                    nt += 1
            i = pair[t, 0]
            j = pair[t, 1]
            for k in range(3):
                acc[i, k] += val[t, k]
                acc[j, k] -= val[t, k]
            energy += val[t, 3]
    for t in range(nt):
        g = touched[t]
        mark[g] = 0
        inv_v = 1.0 / vol[g]
        for k in range(3):
            acc[g, k] *= inv_v
    return nt, energy


@numba.njit(cache=True)
def _add_into(f, offset, touched, nt, acc):
    """f[g - offset] += acc[g] for the touched particles g of the body starting at ``offset``."""
    n = f.shape[0]
    for t in range(nt):
        g = touched[t]
        loc = g - offset
        if 0 <= loc < n:
            f[loc, 0] += acc[g, 0]
            f[loc, 1] += acc[g, 1]
            f[loc, 2] += acc[g, 2]


@numba.njit(cache=True)
def _counted_pairs(counts, cap, pair, val, counted):
    """Number and potential (J) of the found pairs whose first particle is ``counted``."""
    n = 0
    energy = 0.0
    for c in range(counts.shape[0]):
        for t in range(c * cap, c * cap + counts[c]):
            if counted[pair[t, 0]]:
                n += 1
                energy += val[t, 3]
    return n, energy


# --------------------------------------------------------------------------------------------
# the contact object


class ShortRangeContact(ParticleForce):
    """Short-range repulsion among the particles of one or more ice bodies.

    Parameters
    ----------
    bodies
        The ice bodies (:class:`pdfem.pd.body.IceBody`: ``y``, ``x0``, ``vol``, ``dx``,
        ``delta``, ``material.K``, ``f``); a single body may be passed alone. Under MPI, all of
        them :class:`pdfem.pd.distributed.DistributedIce` (every call is then collective, and
        forces go to the owned particles).
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
        Number of interacting pairs found by the last call (over all ranks).
    cell_size
        Side of the search cells, m (the largest critical distance).
    dense, n_buckets
        Whether the last search used the dense grid (else the folded one), and its number of
        buckets (at most ``DENSE_CELLS_PER_PARTICLE * max(N, 1024)``).
    """

    def __init__(self, bodies: "IceBody | Sequence[IceBody]", *, stiffness_factor: float = 15.0,
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
        distributed = [b.distributed for b in self.bodies]
        if any(distributed) and not all(distributed):
            raise ValueError("short-range contact needs all ice bodies split over the ranks "
                             "(DistributedIce) or none")
        # the particles of all bodies, numbered body after body (whole bodies under MPI)
        whole = [b.global_body for b in self.bodies]
        sizes = [int(b.x0.shape[0]) for b in whole]
        self.offsets = np.concatenate(([0], np.cumsum(sizes))).astype(np.int64)
        n = int(self.offsets[-1])
        if n >= 2 ** 31 - 1:
            raise ValueError(f"at most 2**31 - 2 particles in short-range contact, got {n}")
        self.n = n
        self.distance_factor = float(distance_factor)
        self.radius_factor = float(radius_factor)
        self.x0 = np.concatenate([b.x0 for b in whole]).astype(np.float64)
        self.vol = np.concatenate([b.vol for b in whole]).astype(np.float64)
        self.stiffness = np.concatenate([
            np.full(s, short_range_constant(b.material.K, b.delta, stiffness_factor))
            for b, s in zip(whole, sizes)])
        self.radius = np.concatenate([np.full(s, 0.5 * b.dx) for b, s in zip(whole, sizes)])
        self.body = np.concatenate([np.full(s, k, dtype=np.int32) for k, s in enumerate(sizes)])
        dx_max = max(float(b.dx) for b in whole)
        # a margin of 1e-12 keeps pairs at a critical distance of exactly h from being lost to
        # the rounding of the cell coordinates
        self.cell_size = max(self.radius_factor, self.distance_factor) * dx_max * (1.0 + 1e-12)
        threads = int(numba.get_num_threads())
        C = 4 * threads if n_chunks is None else int(n_chunks)
        self._chunks_wanted = max(1, C)
        self.n_chunks = max(1, min(C, max(n, 1)))
        self.chunk_ptr = (np.arange(self.n_chunks + 1, dtype=np.int64) * n) // self.n_chunks
        self._cap = _INITIAL_CAPACITY
        self._pair = np.empty((self.n_chunks * self._cap, 2), dtype=np.int32)
        self._val = np.empty((self.n_chunks * self._cap, 4))
        self._counts = np.zeros(self.n_chunks, dtype=np.int64)
        self._size = -1
        self._dist = _DistributedSearch(self) if all(distributed) else None
        self._reserve(0 if self._dist is not None else n)
        self._n_touched = 0
        self._start = np.empty(1, dtype=np.int64)
        self.n_active = 0
        self.dense = True
        self.n_buckets = 0

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

    def _positions(self) -> np.ndarray:
        if len(self.bodies) == 1:
            return np.ascontiguousarray(self.bodies[0].y, dtype=np.float64)
        return np.concatenate([b.y for b in self.bodies])

    def _grid(self, lo, hi, n_total: int):
        """Cell geometry over the box [lo, hi] for ``n_total`` particles: dims, pad, fold and
        the number of buckets (sets ``dense`` and ``n_buckets``)."""
        inv_h = 1.0 / self.cell_size
        dims = np.array([min(int((hi[k] - lo[k]) * inv_h) + 1, _AXIS_CELLS) for k in range(3)],
                        dtype=np.int64)
        budget = DENSE_CELLS_PER_PARTICLE * max(n_total, 1024)
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
        nb = int(np.prod(fold))
        self.n_buckets = nb
        return dims, pad, fold, nb

    def _scan(self, y, lo, dims, pad, fold, nb, x0, vol, stiffness, radius, body, chunk_ptr,
              counts, shift=_NO_SHIFT):
        """Sort the particles ``y`` (with their constants) into the grid and find the
        interacting pairs into ``self._pair``, ``self._val``, ``counts`` (per chunk)."""
        n = y.shape[0]
        h = self.cell_size
        if self._start.shape[0] != nb + 1:
            self._start = np.empty(nb + 1, dtype=np.int64)
        ijk, key, bucket, perm = self._ijk[:n], self._key[:n], self._bucket[:n], self._perm[:n]
        ys, ijks, keys, buckets = self._ys[:n], self._ijks[:n], self._keys[:n], self._buckets[:n]
        _cells(y, lo, 1.0 / h, dims, pad, fold, ijk, key, bucket, shift)
        _sort(bucket, nb, self._start, perm)
        _gather(perm, y, ijk, key, bucket, ys, ijks, keys, buckets, not self.dense)
        n_chunks = chunk_ptr.shape[0] - 1
        if self._pair.shape[0] < n_chunks * self._cap:
            self._pair = np.empty((n_chunks * self._cap, 2), dtype=np.int32)
            self._val = np.empty((n_chunks * self._cap, 4))
        while True:
            par = n >= SERIAL_BELOW_PARTICLES
            if self.dense:
                _find_dense(par, ys, buckets, self._start, perm, x0, vol, stiffness, radius,
                            body, h, fold, self.distance_factor, self.radius_factor, chunk_ptr,
                            self._cap, self._pair, self._val, counts)
            else:
                _find_folded(par, ys, ijks, keys, buckets, self._start, perm, x0, vol,
                             stiffness, radius, body, h, dims, fold, self.distance_factor,
                             self.radius_factor, chunk_ptr, self._cap, self._pair, self._val,
                             counts)
            most = int(counts.max())
            if most <= self._cap:
                break
            self._cap = 2 * most
            self._pair = np.empty((n_chunks * self._cap, 2), dtype=np.int32)
            self._val = np.empty((n_chunks * self._cap, 4))

    def _search(self) -> float:
        """Find the interacting pairs at the current positions; returns their potential (J)."""
        if self._dist is not None:
            return self._dist.search()
        n = self.n
        self._n_touched = 0
        self.n_active = 0
        if n < 2:
            return 0.0
        y = self._positions()
        lo, hi, finite = _extent(y)
        if not finite:
            raise FloatingPointError(_NOT_FINITE)
        dims, pad, fold, nb = self._grid(lo, hi, n)
        self._scan(y, lo, dims, pad, fold, nb, self.x0, self.vol, self.stiffness, self.radius,
                   self.body, self.chunk_ptr, self._counts)
        self.n_active = int(self._counts.sum())
        if self.n_active == 0:
            return 0.0
        nt, energy = _sum_pairs(self._counts, self._cap, self._pair, self._val, self.vol,
                                self._acc, self._mark, self._touched)
        self._n_touched = nt
        return energy

    # -- public ---------------------------------------------------------------------------------
    def add_forces(self) -> int:
        """Add the short-range force density (N/m^3) at the current positions into each body's f.

        Call after the bodies' peridynamic forces were computed at the same positions.

        Returns
        -------
        int
            The number of interacting pairs.

        Raises
        ------
        FloatingPointError
            If a position is NaN or infinite.
        """
        self._search()
        if self._dist is not None:
            self._dist.add_into([b.f for b in self.bodies])
        elif self._n_touched:
            for b, off in zip(self.bodies, self.offsets[:-1]):
                _add_into(b.f, int(off), self._touched, self._n_touched, self._acc)
        return self.n_active

    def forces(self) -> list[np.ndarray]:
        """The short-range force density (N/m^3) on each body at the current positions.

        Returns
        -------
        list of ndarray
            One (N_b, 3) array per body; the bodies' ``f`` are not touched.
        """
        self._search()
        out = [np.zeros((b.x0.shape[0], 3)) for b in self.bodies]
        if self._dist is not None:
            self._dist.add_into(out)
            return out
        for f, off in zip(out, self.offsets[:-1]):
            _add_into(f, int(off), self._touched, self._n_touched, self._acc)
        return out

    def potential_energy(self) -> float:
        """Potential energy of the short-range force at the current positions, J.

        ``sum over interacting pairs of 1/2 k_ij V_i V_j (r_ij - |y_j - y_i|)^2``.
        """
        return self._search()


class _DistributedSearch:
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
            lo, hi, finite = _extent(y_own)
        else:
            lo, hi, finite = np.full(3, np.inf), np.full(3, -np.inf), True
        boxes = np.array(comm.allgather(np.concatenate([lo, hi, [0.0 if finite else 1.0]])))
        if boxes[:, 6].any():
            raise FloatingPointError(_NOT_FINITE)
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
            shift = _NO_SHIFT
            if c.dense:  # only the cells of the local particles (same cells, same order)
                llo, lhi, _ = _extent(y)
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
            n_pairs, energy = _counted_pairs(counts, c._cap, c._pair, c._val, owned)
            if counts.sum():
                nt, _ = _sum_pairs(counts, c._cap, c._pair, c._val, vol, c._acc, c._mark,
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
