"""The numba loops of the neighbour search (:mod:`pdfem.pd.bonds.search`): cell search and references.

The cell search runs over particles sorted by cell (:mod:`pdfem.geometry.cell_hash`), in
structure-of-arrays form (``xs``, ``ys``, ``zs``), with the runs of occupied cells ``first``.
The references are the O(N^2) brute force and the canonical CSR of scipy's unordered pairs.
The distance test is always ``dx*dx + dy*dy + dz*dz <= r2`` (no fastmath).
"""

from __future__ import annotations

import numba
import numpy as np

from pdfem.geometry.cell_hash import HALF_STENCIL_COLUMNS, cell_id, forward_column

# In cell order the 13 forward neighbour cells of cell (ix, iy, iz) form 4 contiguous particle
# ranges, one per column (dx, dy) = (0, 1), (1, -1), (1, 0), (1, 1), each holding the cells
# iz-1 .. iz+1 of that column (consecutive linear indices); the own cell and the cell above it,
# (ix, iy, iz+1), are contiguous too. Per cell the candidates (own cell, then the 4 columns, in
# increasing index) are gathered once into small local arrays; particle number i of the cell then
# compares itself with candidates i+1 .. end, one contiguous run that vectorises well. The count
# pass sums the test; the fill pass writes the test into a byte mask (vectorised) and compacts
# it into the output row.


@numba.njit(cache=True)
def lower_bound(a, value):
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


@numba.njit(cache=True, parallel=True)
def stencil(sorted_ids, first, nx, ny, nz):
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
        ranges[u, 0, 1] = lower_bound(sorted_ids, cell_id(ix, iy, z1, ny, nz) + 1)
        tot = ranges[u, 0, 1] - s
        for q in range(1, HALF_STENCIL_COLUMNS + 1):
            dx, dy = forward_column(q)
            jx = ix + dx
            jy = iy + dy
            if jx < nx and 0 <= jy < ny:
                base = cell_id(jx, jy, 0, ny, nz)
                ranges[u, q, 0] = lower_bound(sorted_ids, base + z0)
                ranges[u, q, 1] = lower_bound(sorted_ids, base + z1 + 1)
                tot += ranges[u, q, 1] - ranges[u, q, 0]
        work[u] = tot * (first[u + 1] - s) + 1
    return ranges, work


@numba.njit(cache=True)
def gather_candidates(xs, ys, zs, ranges, u, cand, cx, cy, cz):
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
def chunk_capacity(ranges, c0, c1):
    cap = 1
    for u in range(c0, c1):
        tot = 0
        for q in range(5):
            tot += ranges[u, q, 1] - ranges[u, q, 0]
        cap = max(cap, tot)
    return cap


@numba.njit(cache=True, parallel=True)
def count_pass(xs, ys, zs, first, ranges, chunks, r2, counts):
    """counts[a] = number of partners b > a of every particle (sorted numbering)."""
    for ch in numba.prange(chunks.shape[0] - 1):
        c0 = chunks[ch]
        c1 = chunks[ch + 1]
        cap = chunk_capacity(ranges, c0, c1)
        cand = np.empty(cap, dtype=np.int32)
        cx = np.empty(cap)
        cy = np.empty(cap)
        cz = np.empty(cap)
        for u in range(c0, c1):
            m = gather_candidates(xs, ys, zs, ranges, u, cand, cx, cy, cz)
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
def fill_pass(xs, ys, zs, first, ranges, chunks, r2, row_ptr, nbr):
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
        cap = chunk_capacity(ranges, c0, c1)
        cand = np.empty(cap + 8, dtype=np.int32)
        cx = np.empty(cap)
        cy = np.empty(cap)
        cz = np.empty(cap)
        mask64 = np.zeros(cap // 8 + 2, dtype=np.uint64)
        mask = mask64.view(np.uint8)
        buf = np.empty(cap + 8, dtype=np.int32)
        chunk_end = row_ptr[first[c1]]
        for u in range(c0, c1):
            m = gather_candidates(xs, ys, zs, ranges, u, cand, cx, cy, cz)
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
def gather_soa(x, perm):
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


# --------------------------------------------------------------------------------------------
# references


@numba.njit(cache=True)
def brute_count(x, i, r2):
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
def brute_fill(x, i, r2, nbr, k):
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
def brute(x, r2):
    n = x.shape[0]
    counts = np.zeros(n, dtype=np.int64)
    half = (n + 1) // 2
    # rows i and n-1-i together: every iteration does about the same work
    for m in numba.prange(half):
        counts[m] = brute_count(x, m, r2)
        if n - 1 - m != m:
            counts[n - 1 - m] = brute_count(x, n - 1 - m, r2)
    row_ptr = np.empty(n + 1, dtype=np.int64)
    row_ptr[0] = 0
    for i in range(n):
        row_ptr[i + 1] = row_ptr[i] + counts[i]
    nbr = np.empty(row_ptr[n], dtype=np.int32)
    for m in numba.prange(half):
        brute_fill(x, m, r2, nbr, row_ptr[m])
        if n - 1 - m != m:
            brute_fill(x, n - 1 - m, r2, nbr, row_ptr[n - 1 - m])
    return row_ptr, nbr


@numba.njit(cache=True, parallel=True)
def pairs_to_csr(x, pairs, r2):
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
