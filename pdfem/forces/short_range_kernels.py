"""Numba kernels of the short-range contact between ice particles (:mod:`pdfem.forces.short_range`).

The particles are entered into a cell hash (:mod:`pdfem.geometry.cell_hash`): clamped (and on
the dense grid padded) cell coordinates, a packed cell key and a bucket per particle
(:func:`cells`; the bucket is the cell id in the grid folded to ``fold`` cells), then
counting-sorted by bucket (:func:`pdfem.geometry.cell_hash.counting_sort`) and gathered in that
order (:func:`gather`); or, for a rank's particles under MPI, sorted by any stable sort and
indexed by a sparse table of the occupied buckets (:func:`sparse_table`, :func:`first_at`), so
the table is sized from the particles, not from the grid. :func:`find_dense` and
:func:`find_folded` find the interacting pairs per chunk of sorted positions (the physics of
a pair: :func:`interact`); :func:`sum_pairs` adds them up in chunk order (bit-identical for any
chunk or thread count). :func:`load_owned` and :func:`add_owned` serve a rank's
contact halo (:mod:`pdfem.forces.short_range_halo`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np
from numba import prange

from pdfem.geometry.cell_hash import HALF_STENCIL_COLUMNS, cell_id, cell_index, forward_column
from pdfem.parallel.kernels import twin


class Table(NamedTuple):
    """The particles sorted into the cell table: positions ``ys`` (n, 3) m, lattice indices
    ``ijks`` and keys ``keys`` of their cells (folded grids), their buckets, the table
    (``start``, or the sparse ``ub`` with ``start``) and ``perm`` (sorted -> local index)."""

    ys: np.ndarray
    ijks: np.ndarray
    keys: np.ndarray
    buckets: np.ndarray
    start: np.ndarray
    ub: np.ndarray
    perm: np.ndarray


class Constants(NamedTuple):
    """Per local particle: reference position ``x0`` (m), volume (m^3), contact constant k
    (N/m^7), radius dx / 2 (m) and body number."""

    x0: np.ndarray
    vol: np.ndarray
    stiff: np.ndarray
    rad: np.ndarray
    body: np.ndarray


class Grid(NamedTuple):
    """The cell side ``h`` (m), cells per axis ``dims``, buckets per axis ``fold`` and Silling &
    Askari's distance and radius factors."""

    h: float
    dims: np.ndarray
    fold: np.ndarray
    dist_factor: float
    rad_factor: float


class Found(NamedTuple):
    """Where the found pairs go: chunk c (rows ``chunk_ptr[c]:chunk_ptr[c+1]`` of the sorted
    particles) into slots ``[c cap, (c+1) cap)`` of ``pair`` (i, j) and ``val`` (force on i N,
    potential J), its count into ``counts[c]``."""

    chunk_ptr: np.ndarray
    cap: int
    pair: np.ndarray
    val: np.ndarray
    counts: np.ndarray

NOT_FINITE = ("ice particle positions are not finite (NaN or Inf): the run has become "
              "unstable")
NO_SHIFT = np.zeros(3, dtype=np.int64)


@numba.njit(cache=True, inline="always")
def bucket_of(ix, iy, iz, fold):
    """Bucket of cell (ix, iy, iz): its linear index in the grid folded to ``fold`` cells."""
    if ix >= fold[0]:
        ix %= fold[0]
    if iy >= fold[1]:
        iy %= fold[1]
    if iz >= fold[2]:
        iz %= fold[2]
    return cell_id(ix, iy, iz, fold[1], fold[2])


@numba.njit(cache=True, inline="always")
def first_at(start, ub, b):
    """First sorted position of a particle in bucket ``b`` or later: ``start[b]`` of a full
    table (``ub`` empty), or of a sparse one, where ``ub`` lists the occupied buckets
    (ascending) and ``start[t]`` is the first position of bucket ``ub[t]`` (binary search)."""
    n = ub.shape[0]
    if n == 0:
        return start[b]
    lo = 0
    hi = n
    while lo < hi:
        mid = (lo + hi) >> 1
        if ub[mid] < b:
            lo = mid + 1
        else:
            hi = mid
    return start[lo]


@numba.njit(cache=True)
def sparse_table(sorted_buckets, ub, start):
    """The sparse table of :func:`first_at` for buckets sorted ascending: the occupied buckets
    into ``ub``, their first positions into ``start`` (plus the end); returns their number."""
    n = sorted_buckets.shape[0]
    m = 0
    for s in range(n):
        if s == 0 or sorted_buckets[s] != sorted_buckets[s - 1]:
            ub[m] = sorted_buckets[s]
            start[m] = s
            m += 1
    start[m] = n
    return m


@numba.njit(cache=True)
def cells(y, lo, inv_h, dims, pad, fold, ijk, key, bucket, shift):
    """Clamped (and padded) cell coordinates, packed cell key and bucket of every particle;
    the grid's cells start at cell ``shift`` (zeros: at ``lo``)."""
    for i in range(y.shape[0]):
        # clamped as a float before converting: far fragments cannot overflow the integer
        cx = cell_index(y[i, 0], lo[0], inv_h, dims[0]) - shift[0] + pad
        cy = cell_index(y[i, 1], lo[1], inv_h, dims[1]) - shift[1] + pad
        cz = cell_index(y[i, 2], lo[2], inv_h, dims[2]) - shift[2] + pad
        ijk[i, 0] = cx
        ijk[i, 1] = cy
        ijk[i, 2] = cz
        key[i] = (cx << 42) | (cy << 21) | cz
        bucket[i] = bucket_of(cx, cy, cz, fold)


@numba.njit(cache=True)
def gather(perm, y, ijk, key, bucket, ys, ijks, keys, buckets, all_fields):
    """The particles' positions and buckets (``all_fields``: also cells and keys) in sorted order."""
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
def interact(i, j, px, py, pz, d2, x0, vol, stiff, rad, body, dist_factor, rad_factor, store,
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


@twin(fastmath=False, one_thread="parallel")
def find_dense(table, consts, grid, found):
    """Pairs on a dense grid padded by one empty cell on every side, per chunk of sorted
    positions, into the chunk's slots ``[c*cap, (c+1)*cap)``.

    The forward half stencil of a particle's cell is five contiguous runs of sorted positions:
    the own cell after the particle and the cell +z; the three cells +y; and the three columns
    of three cells +x. The runs' bounds are looked up once per cell, in the full table
    ``start`` or in a sparse one (``ub`` not empty, :func:`first_at`). The named tuples
    (:class:`Table`, :class:`Constants`, :class:`Grid`, :class:`Found`) are taken apart
    attribute by attribute before the ``prange``: numba loses writes through tuples inside it,
    and through arrays taken out of a tuple by unpacking (measured).
    """
    ys, buckets, start, ub, perm = table.ys, table.buckets, table.start, table.ub, table.perm
    x0, vol, stiff, rad, body = consts.x0, consts.vol, consts.stiff, consts.rad, consts.body
    h, fold, dist_factor, rad_factor = grid.h, grid.fold, grid.dist_factor, grid.rad_factor
    chunk_ptr, cap, pair, val = found.chunk_ptr, found.cap, found.pair, found.val
    counts = found.counts
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
                run_hi[0] = first_at(start, ub, ba + 2)
                for run in range(1, HALF_STENCIL_COLUMNS + 1):
                    ox, oy = forward_column(run)
                    b = ba + ox * nyz + oy * nz
                    run_lo[run] = first_at(start, ub, b - 1)
                    run_hi[run] = first_at(start, ub, b + 2)
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
                    if interact(perm[a], perm[q], px, py, pz, d2, x0, vol, stiff, rad, body,
                                dist_factor, rad_factor, cnt < cap, base + cnt, pair, val):
                        cnt += 1
        counts[c] = cnt


@twin(fastmath=False, one_thread="parallel")
def find_folded(table, consts, grid, found):
    """:func:`find_dense` for a folded grid: buckets hold several cells, told apart by key.

    Each particle scans the buckets of its 27 neighbour cells that come at or after its own
    bucket, from the sorted position after its own on, and only the particles of the cell asked
    for, so each pair is seen once, from the particle earlier in sorted order."""
    ys, ijks, keys, buckets = table.ys, table.ijks, table.keys, table.buckets
    start, ub, perm = table.start, table.ub, table.perm
    x0, vol, stiff, rad, body = consts.x0, consts.vol, consts.stiff, consts.rad, consts.body
    h, dims, fold = grid.h, grid.dims, grid.fold
    dist_factor, rad_factor = grid.dist_factor, grid.rad_factor
    chunk_ptr, cap, pair, val = found.chunk_ptr, found.cap, found.pair, found.val
    counts = found.counts
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
                            b = bucket_of(ix, iy, iz, fold)
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
                q0 = first_at(start, ub, b)
                if b == ba:
                    q0 = a + 1
                for q in range(q0, first_at(start, ub, b + 1)):
                    if keys[q] != kb:
                        continue
                    px = ys[q, 0] - yax
                    py = ys[q, 1] - yay
                    pz = ys[q, 2] - yaz
                    d2 = px * px + py * py + pz * pz
                    if d2 >= h2:
                        continue
                    if interact(perm[a], perm[q], px, py, pz, d2, x0, vol, stiff, rad, body,
                                dist_factor, rad_factor, cnt < cap, base + cnt, pair, val):
                        cnt += 1
        counts[c] = cnt


@numba.njit(cache=True)
def sum_pairs(counts, cap, pair, val, vol, acc, mark, touched):
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
def add_into(f, offset, touched, nt, acc):
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
def counted_pairs(counts, cap, pair, val, counted):
    """Number and potential (J) of the found pairs whose first particle is ``counted``."""
    n = 0
    energy = 0.0
    for c in range(counts.shape[0]):
        for t in range(c * cap, c * cap + counts[c]):
            if counted[pair[t, 0]]:
                n += 1
                energy += val[t, 3]
    return n, energy


@numba.njit(cache=True)
def load_owned(y_body, idx, pos, y, y_ref, box, drift):
    """Owned positions into the local array: ``y[pos[t]] = y_body[idx[t]]`` (m), while growing
    the box ``box`` ((2, 3): lo, hi) and returning whether they are all finite and the largest
    squared distance (m^2) from ``y_ref[pos[t]]``, at least ``drift``."""
    finite = True
    for t in range(idx.shape[0]):
        i = idx[t]
        p = pos[t]
        d2 = 0.0
        for k in range(3):
            v = y_body[i, k]
            y[p, k] = v
            if not math.isfinite(v):
                finite = False
            if v < box[0, k]:
                box[0, k] = v
            if v > box[1, k]:
                box[1, k] = v
            e = v - y_ref[p, k]
            d2 += e * e
        if d2 > drift:
            drift = d2
    return finite, drift


@numba.njit(cache=True)
def add_owned(f, idx, pos, acc, touched, nt, mark):
    """``f[idx[t]] += acc[pos[t]]`` for the owned particles touched by the last search
    (``touched[:nt]``; ``mark``, zeros, of the local size, is left zero)."""
    for t in range(nt):
        mark[touched[t]] = 1
    for t in range(idx.shape[0]):
        p = pos[t]
        if mark[p]:
            i = idx[t]
            for k in range(3):
                f[i, k] += acc[p, k]
    for t in range(nt):
        mark[touched[t]] = 0
