"""Numba kernels of the short-range contact's candidate search (:mod:`pdfem.forces.short_range`).

The search runs only when the Verlet pair list is built (at a refresh of the contact halo). The
local particles are entered into a cell hash (:mod:`pdfem.geometry.cell_hash`) of side h + s
over their own box: clamped (and on the dense grid padded) cell coordinates, a packed cell key
and a bucket per particle (:func:`cells`; the bucket is the cell id in the grid folded to
``fold`` cells), then counting-sorted by bucket
(:func:`pdfem.geometry.cell_hash.counting_sort`) and gathered in that order (:func:`gather`).
:func:`find_dense` and :func:`find_folded` find the candidate pairs per chunk of sorted
positions, each with its constants (:func:`candidate`); the pair list made of them and the
per-step force pass are :mod:`pdfem.forces.short_range_list_kernels`. :func:`load_owned`
serves a rank's contact halo (:mod:`pdfem.forces.short_range_halo`).
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
    ``start`` (bucket b holds sorted positions ``start[b]:start[b + 1]``) and ``perm`` (sorted
    -> local index)."""

    ys: np.ndarray
    ijks: np.ndarray
    keys: np.ndarray
    buckets: np.ndarray
    start: np.ndarray
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
    """The cell side ``h`` (m, at least the largest critical distance plus the skin), cells per
    axis ``dims``, buckets per axis ``fold``, Silling & Askari's distance and radius factors and
    the Verlet skin ``skin`` (m)."""

    h: float
    dims: np.ndarray
    fold: np.ndarray
    dist_factor: float
    rad_factor: float
    skin: float


class Found(NamedTuple):
    """Where the found candidates go: chunk c (rows ``chunk_ptr[c]:chunk_ptr[c+1]`` of the
    sorted particles) into slots ``[c cap, (c+1) cap)`` of ``pair`` (i < j, local indices) and
    ``val`` (critical distance r_ij m, k_ij V_i V_j N m), its count into ``counts[c]``."""

    chunk_ptr: np.ndarray
    cap: int
    pair: np.ndarray
    val: np.ndarray
    counts: np.ndarray


NOT_FINITE = ("ice particle positions are not finite (NaN or Inf): the run has become "
              "unstable")


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


@numba.njit(cache=True)
def cells(y, lo, inv_h, dims, pad, fold, ijk, key, bucket):
    """Clamped (and padded) cell coordinates, packed cell key and bucket of every particle."""
    for i in range(y.shape[0]):
        # clamped as a float before converting: far fragments cannot overflow the integer
        cx = cell_index(y[i, 0], lo[0], inv_h, dims[0]) + pad
        cy = cell_index(y[i, 1], lo[1], inv_h, dims[1]) + pad
        cz = cell_index(y[i, 2], lo[2], inv_h, dims[2]) + pad
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
def candidate(a, b, d2, x0, vol, stiff, rad, body, dist_factor, rad_factor, skin, store, slot,
              pair, val):
    """Whether local particles a, b (|y_b - y_a|^2 = d2) are a candidate pair, closer than
    their critical distance r_ij plus the skin; if so and ``store``, write the pair as (i, j),
    i < j, its r_ij (m) and k_ij V_i V_j (N m) into ``slot``. The constants are computed from
    the lower index's side, so they are the same bits whichever particle found the pair."""
    i = min(a, b)
    j = max(a, b)
    rsum = rad[i] + rad[j]
    if body[i] == body[j]:
        ex = x0[j, 0] - x0[i, 0]
        ey = x0[j, 1] - x0[i, 1]
        ez = x0[j, 2] - x0[i, 2]
        r = min(dist_factor * math.sqrt(ex * ex + ey * ey + ez * ez), rad_factor * rsum)
    else:
        r = dist_factor * rsum
    reach = r + skin
    if d2 >= reach * reach:
        return False
    if store:
        pair[slot, 0] = i
        pair[slot, 1] = j
        val[slot, 0] = r
        val[slot, 1] = 2.0 * stiff[i] * stiff[j] / (stiff[i] + stiff[j]) * vol[i] * vol[j]
    return True


@twin(fastmath=False, one_thread="parallel")
def find_dense(table, consts, grid, found):
    """Candidate pairs on a dense grid padded by one empty cell on every side, per chunk of
    sorted positions, into the chunk's slots ``[c*cap, (c+1)*cap)``.

    The forward half stencil of a particle's cell is five contiguous runs of sorted positions:
    the own cell after the particle and the cell +z; the three cells +y; and the three columns
    of three cells +x. The runs' bounds are looked up once per cell in the table ``start``.
    The named tuples (:class:`Table`, :class:`Constants`, :class:`Grid`, :class:`Found`) are
    taken apart attribute by attribute before the ``prange``: numba loses writes through tuples
    inside it, and through arrays taken out of a tuple by unpacking (measured).
    """
    ys, buckets, start, perm = table.ys, table.buckets, table.start, table.perm
    x0, vol, stiff, rad, body = consts.x0, consts.vol, consts.stiff, consts.rad, consts.body
    h, fold, dist_factor, rad_factor = grid.h, grid.fold, grid.dist_factor, grid.rad_factor
    skin = grid.skin
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
                run_hi[0] = start[ba + 2]
                for run in range(1, HALF_STENCIL_COLUMNS + 1):
                    ox, oy = forward_column(run)
                    b = ba + ox * nyz + oy * nz
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
                    if candidate(perm[a], perm[q], d2, x0, vol, stiff, rad, body, dist_factor,
                                 rad_factor, skin, cnt < cap, base + cnt, pair, val):
                        cnt += 1
        counts[c] = cnt


@twin(fastmath=False, one_thread="parallel")
def find_folded(table, consts, grid, found):
    """:func:`find_dense` for a folded grid: buckets hold several cells, told apart by key.

    Each particle scans the buckets of its 27 neighbour cells that come at or after its own
    bucket, from the sorted position after its own on, and only the particles of the cell asked
    for, so each pair is seen once, from the particle earlier in sorted order."""
    ys, ijks, keys, buckets = table.ys, table.ijks, table.keys, table.buckets
    start, perm = table.start, table.perm
    x0, vol, stiff, rad, body = consts.x0, consts.vol, consts.stiff, consts.rad, consts.body
    h, dims, fold = grid.h, grid.dims, grid.fold
    dist_factor, rad_factor, skin = grid.dist_factor, grid.rad_factor, grid.skin
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
                    if candidate(perm[a], perm[q], d2, x0, vol, stiff, rad, body, dist_factor,
                                 rad_factor, skin, cnt < cap, base + cnt, pair, val):
                        cnt += 1
        counts[c] = cnt


@numba.njit(cache=True)
def load_owned(y_body, idx, pos, y, y_ref, box, drift):
    """Owned positions into the local array: ``y[pos[t]] = y_body[idx[t]]`` (m), while growing
    the box ``box`` ((2, 3): lo, hi) and returning whether they are all finite, the largest
    squared distance (m^2) from ``y_ref[pos[t]]``, at least ``drift``, and whether any
    position differs from the one ``y`` held (bit for bit)."""
    finite = True
    moved = False
    for t in range(idx.shape[0]):
        i = idx[t]
        p = pos[t]
        d2 = 0.0
        for k in range(3):
            v = y_body[i, k]
            if v != y[p, k]:
                moved = True
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
    return finite, drift, moved
