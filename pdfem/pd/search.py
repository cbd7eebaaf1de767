"""Neighbour search: all unique particle pairs closer than the horizon (the bond list).

The production search is the "updated link-list" (cell) method of the seed paper
(Zhang et al. 2023): particles are sorted by the cell of a grid of side ``delta`` that holds them,
then each particle is compared only with the later particles of its own cell and with the
particles of the 13 "forward" neighbour cells (a half stencil), so every pair is found once.

A pair is ``(i, j)``, ``i < j``, with ``|x_i - x_j| <= delta``, decided by exactly the same
floating-point test in every implementation here::

    d = x[j] - x[i];  d[0]*d[0] + d[1]*d[1] + d[2]*d[2] <= delta*delta

(the order of a pair does not matter: x[i] - x[j] is exactly -(x[j] - x[i]) in IEEE arithmetic;
no fastmath here, so no fused multiply-adds), hence the brute-force, cKDTree and cell searches
return identical sets. Pairs are stored CSR-like,
grouped by their first index: ``row_ptr`` (N+1,) int64 and ``nbr`` (P,) int32, the pairs of ``i``
being ``(i, nbr[k])`` for ``k`` in ``row_ptr[i]:row_ptr[i+1]``, with ``i < nbr[k]`` and ``nbr``
ascending within each group.

:func:`cell_pairs` is what the builders use. :func:`brute_pairs` (O(N^2)) and
:func:`ckdtree_pairs` (scipy) are references for tests and the benchmark.
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["cell_sort", "cell_pairs", "search_cell_size", "brute_pairs", "ckdtree_pairs", "pairs_to_array"]

#: dense counting sort while the grid has at most this many cells per particle (else argsort)
_DENSE_CELLS_PER_PARTICLE = 4


# --------------------------------------------------------------------------------------------
# input checks


def _as_points(x) -> np.ndarray:
    x = np.ascontiguousarray(x, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"particle positions must be an (N, 3) array, got shape {x.shape}")
    if x.shape[0] >= 2 ** 31 - 1:
        raise ValueError(f"at most 2**31 - 2 particles per search (int32 indices), got {x.shape[0]}")
    if x.shape[0] and not np.all(np.isfinite(x)):
        raise ValueError("particle positions must be finite (found NaN or Inf)")
    return x


def _check_length(value: float, name: str) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"the {name} must be a positive finite length in m, got {value!r}")
    return value


# --------------------------------------------------------------------------------------------
# cell sort


@numba.njit(cache=True)
def _extent(x):
    """Per-axis minimum and maximum of x (N >= 1)."""
    lo = x[0].copy()
    hi = x[0].copy()
    for i in range(1, x.shape[0]):
        for k in range(3):
            v = x[i, k]
            if v < lo[k]:
                lo[k] = v
            elif v > hi[k]:
                hi[k] = v
    return lo, hi


def _grid(lo: np.ndarray, hi: np.ndarray, cell_size: float) -> list[int]:
    """Cells per axis of the grid of side ``cell_size`` anchored at ``lo`` that covers ``hi``."""
    inv_h = 1.0 / cell_size
    span = [(hi[k] - lo[k]) * inv_h for k in range(3)]
    if max(span) >= 2.0 ** 52:
        raise ValueError(f"the cell size {cell_size:g} m is too small for the extent of the particles "
                         f"({float(np.max(hi - lo)):g} m): more than 2**52 cells along an axis")
    return [int(math.floor(v)) + 1 for v in span]


@numba.njit(cache=True, parallel=True)
def _cell_ids(x, lo, inv_h, nx, ny, nz):
    n = x.shape[0]
    ids = np.empty(n, dtype=np.int64)
    for i in numba.prange(n):
        ix = min(int(math.floor((x[i, 0] - lo[0]) * inv_h)), nx - 1)
        iy = min(int(math.floor((x[i, 1] - lo[1]) * inv_h)), ny - 1)
        iz = min(int(math.floor((x[i, 2] - lo[2]) * inv_h)), nz - 1)
        ids[i] = (ix * ny + iy) * nz + iz
    return ids


@numba.njit(cache=True, parallel=True)
def _cell_coords(x, lo, inv_h, dims):
    n = x.shape[0]
    ijk = np.empty((n, 3), dtype=np.int64)
    for i in numba.prange(n):
        for k in range(3):
            ijk[i, k] = min(int(math.floor((x[i, k] - lo[k]) * inv_h)), dims[k] - 1)
    return ijk


@numba.njit(cache=True)
def _counting_sort(ids, ncells):
    """Stable O(N + ncells) sort of ``ids``: returns the permutation."""
    n = ids.shape[0]
    start = np.zeros(ncells + 1, dtype=np.int64)
    for i in range(n):
        start[ids[i] + 1] += 1
    for c in range(ncells):
        start[c + 1] += start[c]
    perm = np.empty(n, dtype=np.int64)
    for i in range(n):
        c = ids[i]
        perm[start[c]] = i
        start[c] += 1
    return perm


def _sort_by_cell(x: np.ndarray, lo: np.ndarray, hi: np.ndarray, cell_size: float):
    """``perm``, the sorted cell ids and the grid dimensions (x checked, N >= 1).

    A grid of more than 2**62 cells (a tiny cell for the extent) is first compressed: along each
    axis the occupied cell coordinates are renumbered 0, 1, 2, ... in order. That keeps the order
    of the cells and the adjacency of occupied ones (cells adjacent before are adjacent after;
    some that were not become so, which only adds candidates that the distance test rejects).
    """
    dims = _grid(lo, hi, cell_size)
    inv_h = 1.0 / cell_size
    # cell coordinates from (x - lo) * (1/h): the same monotone expression for every particle
    if float(dims[0]) * dims[1] * dims[2] <= 2.0 ** 62:
        ids = _cell_ids(x, lo, inv_h, dims[0], dims[1], dims[2])
    else:
        ijk = _cell_coords(x, lo, inv_h, np.asarray(dims, dtype=np.int64))
        for k in range(3):
            occupied, ijk[:, k] = np.unique(ijk[:, k], return_inverse=True)
            dims[k] = occupied.shape[0]
        if float(dims[0]) * dims[1] * dims[2] > 2.0 ** 62:
            raise ValueError(f"the cell size {cell_size:g} m is too small for the extent of the particles "
                             f"({float(np.max(hi - lo)):g} m): the grid has more than 2**62 cells")
        ids = (ijk[:, 0] * dims[1] + ijk[:, 1]) * dims[2] + ijk[:, 2]
    nx, ny, nz = dims
    ncells = nx * ny * nz
    if ncells <= _DENSE_CELLS_PER_PARTICLE * x.shape[0] + 1024:
        perm = _counting_sort(ids, ncells)
    else:
        perm = np.argsort(ids, kind="stable").astype(np.int64)
    return perm, ids[perm], (nx, ny, nz)


def cell_sort(x: np.ndarray, cell_size: float) -> np.ndarray:
    """Permutation that orders particles by the cell that holds them.

    The grid has cubic cells of side ``cell_size`` anchored at ``x.min(axis=0)``; a particle's
    cell is ``i_k = floor((x_k - lo_k) / cell_size)`` (computed as ``(x_k - lo_k) * (1 /
    cell_size)``) and its linear index ``c = (ix * ny + iy) * nz + iz``. Particles of one cell keep
    their original order (stable). Counting sort, O(N), unless the grid has many more cells than
    there are particles (then a stable argsort). A grid of more than 2**62 cells is numbered after
    renumbering the occupied coordinates of each axis 0, 1, 2, ... (same order).

    Parameters
    ----------
    x
        (N,3) particle positions, m.
    cell_size
        Side of the cubic cells, m (> 0).

    Returns
    -------
    ndarray
        (N,) int64 permutation: ``x[perm]`` is in cell order.
    """
    x = _as_points(x)
    cell_size = _check_length(cell_size, "cell size")
    if x.shape[0] == 0:
        return np.zeros(0, dtype=np.int64)
    lo, hi = _extent(x)
    return _sort_by_cell(x, lo, hi, cell_size)[0]


def search_cell_size(x: np.ndarray, delta: float) -> float:
    """Cell side (m) that :func:`cell_pairs` uses for the horizon ``delta`` (m).

    ``delta`` enlarged by a relative 1e-9 (more on grids of over a million cells per axis): this
    guarantees that two particles that pass the distance test ``d2 <= delta**2`` lie in the same
    or in adjacent cells despite rounding in the cell coordinates.
    """
    x = _as_points(x)
    delta = _check_length(delta, "horizon")
    if x.shape[0] == 0:
        return delta
    lo, hi = _extent(x)
    return _search_cell_size(lo, hi, delta)


def _search_cell_size(lo: np.ndarray, hi: np.ndarray, delta: float) -> float:
    ncell = float(np.max(hi - lo)) / delta
    return delta * (1.0 + 1e-9 + 8e-16 * ncell)


# --------------------------------------------------------------------------------------------
# cell search
#
# In cell order the 13 forward neighbour cells of cell (ix, iy, iz) form 4 contiguous particle
# ranges, one per column (dx, dy) = (0, 1), (1, -1), (1, 0), (1, 1), each holding the cells
# iz-1 .. iz+1 of that column (consecutive linear indices); the own cell and the cell above it,
# (ix, iy, iz+1), are contiguous too. Per cell the candidates (own cell, then the 4 columns, in
# increasing index) are gathered once into small local arrays; particle number i of the cell then
# compares itself with candidates i+1 .. end, one contiguous run that vectorises well. The count
# pass sums the test; the fill pass writes the test into a byte mask (vectorised) and compacts
# it into the output row.


@numba.njit(cache=True)
def _lower_bound(a, value):
    """First index k with a[k] >= value (a sorted ascending)."""
    lo = 0
    hi = a.shape[0]
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] < value:
            lo = mid + 1
        else:
            hi = mid
    return lo


@numba.njit(cache=True)
def _cell_starts(sorted_ids):
    """Start of every occupied cell in the sorted order, plus the end: (M+1,) int64."""
    n = sorted_ids.shape[0]
    m = 1
    for i in range(1, n):
        if sorted_ids[i] != sorted_ids[i - 1]:
            m += 1
    first = np.empty(m + 1, dtype=np.int64)
    first[0] = 0
    k = 1
    for i in range(1, n):
        if sorted_ids[i] != sorted_ids[i - 1]:
            first[k] = i
            k += 1
    first[m] = n
    return first


@numba.njit(cache=True, parallel=True)
def _stencil(sorted_ids, first, nx, ny, nz):
    """Candidate ranges of every occupied cell: (M, 5, 2) int64 and the work estimate (M,).

    Row 0 is the own cell plus the cell above; rows 1-4 the forward columns (empty: 0, 0).
    """
    m = first.shape[0] - 1
    ranges = np.zeros((m, 5, 2), dtype=np.int64)
    work = np.empty(m, dtype=np.int64)
    for u in numba.prange(m):
        s = first[u]
        c = sorted_ids[s]
        iz = c % nz
        iy = (c // nz) % ny
        ix = c // (ny * nz)
        z0 = max(iz - 1, 0)
        z1 = min(iz + 1, nz - 1)
        ranges[u, 0, 0] = s
        ranges[u, 0, 1] = _lower_bound(sorted_ids, (ix * ny + iy) * nz + z1 + 1)
        tot = ranges[u, 0, 1] - s
        for q in range(1, 5):
            if q == 1:
                jx = ix
                jy = iy + 1
            else:
                jx = ix + 1
                jy = iy + q - 3
            if jx < nx and 0 <= jy < ny:
                base = (jx * ny + jy) * nz
                ranges[u, q, 0] = _lower_bound(sorted_ids, base + z0)
                ranges[u, q, 1] = _lower_bound(sorted_ids, base + z1 + 1)
                tot += ranges[u, q, 1] - ranges[u, q, 0]
        work[u] = tot * (first[u + 1] - s) + 1
    return ranges, work


def _chunks(work: np.ndarray, nchunk: int) -> np.ndarray:
    """Split the cells into up to ``nchunk`` consecutive runs of about equal work."""
    cum = np.cumsum(work)
    targets = cum[-1] * np.arange(1, nchunk) / nchunk
    inner = np.searchsorted(cum, targets, side="right")
    return np.unique(np.concatenate([[0], inner, [work.shape[0]]])).astype(np.int64)


@numba.njit(cache=True)
def _gather_candidates(xs, ys, zs, ranges, u, cand, cx, cy, cz):
    """Copy the candidates of cell ``u`` (own cell first) to the local arrays; return how many."""
    m = 0
    for q in range(5):
        for b in range(ranges[u, q, 0], ranges[u, q, 1]):
            cand[m] = b
            cx[m] = xs[b]
            cy[m] = ys[b]
            cz[m] = zs[b]
            m += 1
    return m


@numba.njit(cache=True)
def _chunk_capacity(ranges, c0, c1):
    cap = 1
    for u in range(c0, c1):
        tot = 0
        for q in range(5):
            tot += ranges[u, q, 1] - ranges[u, q, 0]
        cap = max(cap, tot)
    return cap


@numba.njit(cache=True, parallel=True)
def _count_pass(xs, ys, zs, first, ranges, chunks, r2, counts):
    """counts[a] = number of partners b > a of every particle (sorted numbering)."""
    for ch in numba.prange(chunks.shape[0] - 1):
        c0 = chunks[ch]
        c1 = chunks[ch + 1]
        cap = _chunk_capacity(ranges, c0, c1)
        cand = np.empty(cap, dtype=np.int32)
        cx = np.empty(cap)
        cy = np.empty(cap)
        cz = np.empty(cap)
        for u in range(c0, c1):
            m = _gather_candidates(xs, ys, zs, ranges, u, cand, cx, cy, cz)
            s = first[u]
            for i in range(first[u + 1] - s):
                xa = cx[i]
                ya = cy[i]
                za = cz[i]
                c = 0
                # unsigned loop bounds: no negative-index wraparound, so the loop vectorises
                for t in range(np.uint64(i + 1), np.uint64(m)):
                    dx = cx[t] - xa
                    dy = cy[t] - ya
                    dz = cz[t] - za
                    c += dx * dx + dy * dy + dz * dz <= r2
                counts[s + i] = c


@numba.njit(cache=True, parallel=True)
def _fill_pass(xs, ys, zs, first, ranges, chunks, r2, row_ptr, nbr):
    """Write the partners of every particle into its CSR row; return the number of bad rows (0).

    Per particle: the distance test into a byte mask (vectorised), then a branch-free compaction
    of the candidates whose byte is set, skipping 8-byte words of the mask that are all zero
    (most are: accepted candidates cluster). Rows that are not the last non-empty row of their
    chunk are written in place: a rejected candidate may land one past the row's end, a slot
    that a later row of the same chunk overwrites. The others go through a local buffer.
    """
    nch = chunks.shape[0] - 1
    bad = np.zeros(nch, dtype=np.int64)
    for ch in numba.prange(nch):
        c0 = chunks[ch]
        c1 = chunks[ch + 1]
        cap = _chunk_capacity(ranges, c0, c1)
        cand = np.empty(cap + 8, dtype=np.int32)
        cx = np.empty(cap)
        cy = np.empty(cap)
        cz = np.empty(cap)
        mask64 = np.zeros(cap // 8 + 2, dtype=np.uint64)
        mask = mask64.view(np.uint8)
        buf = np.empty(cap + 8, dtype=np.int32)
        chunk_end = row_ptr[first[c1]]
        for u in range(c0, c1):
            m = _gather_candidates(xs, ys, zs, ranges, u, cand, cx, cy, cz)
            s = first[u]
            for i in range(first[u + 1] - s):
                a = s + i
                xa = cx[i]
                ya = cy[i]
                za = cz[i]
                lo = i + 1
                n_cand = m - lo
                for t in range(np.uint64(n_cand)):
                    tt = t + np.uint64(lo)
                    dx = cx[tt] - xa
                    dy = cy[tt] - ya
                    dz = cz[tt] - za
                    mask[t] = dx * dx + dy * dy + dz * dz <= r2
                n_words = (n_cand + 7) >> 3
                for t in range(n_cand, n_words * 8):
                    mask[t] = 0
                r0 = row_ptr[a]
                r1 = row_ptr[a + 1]
                direct = r1 < chunk_end
                out = nbr if direct else buf
                k = np.uint64(r0) if direct else np.uint64(0)
                for w in range(np.uint64(n_words)):
                    word = mask64[w]
                    if word != 0:
                        t0 = np.uint64(lo) + w * np.uint64(8)
                        for j in range(np.uint64(8)):
                            out[k] = cand[t0 + j]
                            k += (word >> (j * np.uint64(8))) & np.uint64(1)
                if direct:
                    if k != np.uint64(r1):
                        bad[ch] += 1
                elif k != np.uint64(r1 - r0):
                    bad[ch] += 1
                else:
                    for t in range(r1 - r0):
                        nbr[r0 + t] = buf[t]
    return bad.sum()


@numba.njit(cache=True, parallel=True)
def _gather_soa(x, perm):
    n = perm.shape[0]
    xs = np.empty(n)
    ys = np.empty(n)
    zs = np.empty(n)
    for i in numba.prange(n):
        p = perm[i]
        xs[i] = x[p, 0]
        ys[i] = x[p, 1]
        zs[i] = x[p, 2]
    return xs, ys, zs


def cell_pairs(x: np.ndarray, delta: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """All unique pairs within ``delta`` by the cell (link-list) method with a half stencil.

    The particles are sorted by cell (:func:`cell_sort` with the cell side
    :func:`search_cell_size`, i.e. ``delta`` enlarged by a relative ~1e-9 so that rounding cannot
    put a pair in non-adjacent cells); in that sorted numbering particle ``a`` of cell ``c`` is
    compared with the later particles of ``c`` and with all particles of the 13 neighbour cells
    of larger linear index, visited in increasing linear index. Every pair therefore has
    ``a < b`` and comes out grouped by ``a`` with ``b`` ascending. Parallel over runs of cells of
    equal work: a count pass, a prefix sum and a fill pass.

    Parameters
    ----------
    x
        (N,3) particle positions, m.
    delta
        Horizon, m (> 0); a pair is ``d2 <= delta*delta``.

    Returns
    -------
    perm
        (N,) int64: the sorted numbering, i.e. sorted particle ``a`` is ``x[perm[a]]``.
    row_ptr
        (N+1,) int64 CSR offsets (sorted numbering).
    nbr
        (P,) int32 second indices (sorted numbering).
    """
    x = _as_points(x)
    delta = _check_length(delta, "horizon")
    n = x.shape[0]
    if n == 0:
        return np.zeros(0, np.int64), np.zeros(1, np.int64), np.zeros(0, np.int32)
    lo, hi = _extent(x)
    perm, sorted_ids, (nx, ny, nz) = _sort_by_cell(x, lo, hi, _search_cell_size(lo, hi, delta))
    xs, ys, zs = _gather_soa(x, perm)
    first = _cell_starts(sorted_ids)
    ranges, work = _stencil(sorted_ids, first, nx, ny, nz)
    chunks = _chunks(work, 8 * numba.get_num_threads())
    r2 = delta * delta
    # the large outputs are allocated by numpy (which asks the kernel for huge pages)
    row_ptr = np.empty(n + 1, dtype=np.int64)
    row_ptr[0] = 0
    _count_pass(xs, ys, zs, first, ranges, chunks, r2, row_ptr[1:])
    np.cumsum(row_ptr[1:], out=row_ptr[1:])
    nbr = np.empty(int(row_ptr[n]), dtype=np.int32)
    if _fill_pass(xs, ys, zs, first, ranges, chunks, r2, row_ptr, nbr) != 0:
        raise RuntimeError("cell search: the fill pass disagrees with the count pass (a bug)")
    return perm, row_ptr, nbr


# --------------------------------------------------------------------------------------------
# references


@numba.njit(cache=True)
def _brute_count(x, i, r2):
    """Number of partners j > i of particle i."""
    cnt = 0
    xi = x[i, 0]
    yi = x[i, 1]
    zi = x[i, 2]
    for j in range(np.uint64(i + 1), np.uint64(x.shape[0])):
        dx = x[j, 0] - xi
        dy = x[j, 1] - yi
        dz = x[j, 2] - zi
        cnt += dx * dx + dy * dy + dz * dz <= r2
    return cnt


@numba.njit(cache=True)
def _brute_fill(x, i, r2, nbr, k):
    """Write the partners j > i of particle i at ``nbr[k:]``, ascending."""
    xi = x[i, 0]
    yi = x[i, 1]
    zi = x[i, 2]
    for j in range(i + 1, x.shape[0]):
        dx = x[j, 0] - xi
        dy = x[j, 1] - yi
        dz = x[j, 2] - zi
        if dx * dx + dy * dy + dz * dz <= r2:
            nbr[k] = j
            k += 1


@numba.njit(cache=True, parallel=True)
def _brute(x, r2):
    n = x.shape[0]
    counts = np.zeros(n, dtype=np.int64)
    half = (n + 1) // 2
    # rows i and n-1-i together: every iteration does about the same work
    for m in numba.prange(half):
        counts[m] = _brute_count(x, m, r2)
        if n - 1 - m != m:
            counts[n - 1 - m] = _brute_count(x, n - 1 - m, r2)
    row_ptr = np.empty(n + 1, dtype=np.int64)
    row_ptr[0] = 0
    for i in range(n):
        row_ptr[i + 1] = row_ptr[i] + counts[i]
    nbr = np.empty(row_ptr[n], dtype=np.int32)
    for m in numba.prange(half):
        _brute_fill(x, m, r2, nbr, row_ptr[m])
        if n - 1 - m != m:
            _brute_fill(x, n - 1 - m, r2, nbr, row_ptr[n - 1 - m])
    return row_ptr, nbr


def brute_pairs(x: np.ndarray, delta: float) -> tuple[np.ndarray, np.ndarray]:
    """All unique pairs within ``delta`` by comparing every pair (O(N^2); a reference).

    Parameters
    ----------
    x
        (N,3) particle positions, m.
    delta
        Horizon, m (> 0).

    Returns
    -------
    row_ptr, nbr
        CSR in the given numbering: (N+1,) int64 and (P,) int32, ``i < nbr``, ascending per row.
    """
    x = _as_points(x)
    delta = _check_length(delta, "horizon")
    return _brute(x, delta * delta)


@numba.njit(cache=True, parallel=True)
def _pairs_to_csr(x, pairs, r2):
    """Canonical CSR from unordered (P,2) pairs, keeping those with d2 <= r2."""
    n = x.shape[0]
    p = pairs.shape[0]
    keep = np.empty(p, dtype=np.bool_)
    for k in numba.prange(p):
        i = pairs[k, 0]
        j = pairs[k, 1]
        dx = x[j, 0] - x[i, 0]
        dy = x[j, 1] - x[i, 1]
        dz = x[j, 2] - x[i, 2]
        keep[k] = i != j and dx * dx + dy * dy + dz * dz <= r2
    row_ptr = np.zeros(n + 1, dtype=np.int64)
    for k in range(p):
        if keep[k]:
            row_ptr[min(pairs[k, 0], pairs[k, 1]) + 1] += 1
    for i in range(n):
        row_ptr[i + 1] += row_ptr[i]
    pos = row_ptr[:-1].copy()
    nbr = np.empty(row_ptr[n], dtype=np.int32)
    for k in range(p):
        if keep[k]:
            i = min(pairs[k, 0], pairs[k, 1])
            nbr[pos[i]] = max(pairs[k, 0], pairs[k, 1])
            pos[i] += 1
    for i in numba.prange(n):
        nbr[row_ptr[i]:row_ptr[i + 1]].sort()
    return row_ptr, nbr


def ckdtree_pairs(x: np.ndarray, delta: float) -> tuple[np.ndarray, np.ndarray]:
    """All unique pairs within ``delta`` from scipy's cKDTree (a reference and benchmark rival).

    The tree is queried with a radius enlarged by a relative 1e-9 and the candidates are then
    filtered with the common test ``d2 <= delta*delta``, so the set is identical to the other
    searches'.

    Parameters
    ----------
    x
        (N,3) particle positions, m.
    delta
        Horizon, m (> 0).

    Returns
    -------
    row_ptr, nbr
        CSR in the given numbering: (N+1,) int64 and (P,) int32, ``i < nbr``, ascending per row.
    """
    from scipy.spatial import cKDTree

    x = _as_points(x)
    delta = _check_length(delta, "horizon")
    n = x.shape[0]
    if n < 2:
        return np.zeros(n + 1, np.int64), np.zeros(0, np.int32)
    tree = cKDTree(x)
    pairs = tree.query_pairs(delta * (1.0 + 1e-9), output_type="ndarray")
    return _pairs_to_csr(x, np.ascontiguousarray(pairs, dtype=np.int64), delta * delta)


def pairs_to_array(row_ptr: np.ndarray, nbr: np.ndarray) -> np.ndarray:
    """Expand CSR pairs into a (P,2) int64 array of ``(i, j)`` rows, in CSR order.

    Parameters
    ----------
    row_ptr
        (N+1,) int64 offsets.
    nbr
        (P,) second indices.
    """
    row_ptr = np.asarray(row_ptr, dtype=np.int64)
    n = row_ptr.shape[0] - 1
    out = np.empty((nbr.shape[0], 2), dtype=np.int64)
    out[:, 0] = np.repeat(np.arange(n, dtype=np.int64), np.diff(row_ptr))
    out[:, 1] = nbr
    return out
