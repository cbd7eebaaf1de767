"""The uniform cell hash shared by every spatial search: cells of points, sorting by cell.

A grid of cubic cells of side h anchored at a corner ``lo``; a point's cell along an axis is
``floor((p - lo) * inv_h)`` (always this expression, with ``inv_h = 1 / h``, so that every
search puts a point in the same cell), its linear cell id ``(ix * ny + iy) * nz + iz``. Users:

- the neighbour search of the bonds (:mod:`pdfem.pd.bonds.search`): points counting-sorted by cell,
  runs of equal cell ids, half stencil of forward columns;
- short-range contact between ice particles (:mod:`pdfem.forces.short_range_kernels`): the
  same sort by (possibly folded) cell, the same half stencil on the dense grid;
- the facet grid of the surface contact (:mod:`pdfem.coupling.facet_grid`) and the column grid
  of the closed-surface point test (:mod:`pdfem.geometry.ray_parity_kernels`): boxes entered in
  every cell they overlap (:func:`bin_boxes`).

Plain numba functions over flat arrays; the small ones are ``inline="always"``, so they compile
into the caller's loop with the caller's flags (no call, identical arithmetic).
"""

from __future__ import annotations

import math

import numba
import numpy as np

#: the 4 forward columns (dx, dy) of the half stencil, q = 1..4; with the own column's cells
#: above the own cell they are the 13 forward neighbours of a cell
HALF_STENCIL_COLUMNS = 4


@numba.njit(cache=True)
def bounding_box(x):
    """Per-axis minimum and maximum of the (N, 3) points ``x`` (N >= 1), and whether all of
    their coordinates are finite."""
    lo = np.empty(3)
    hi = np.empty(3)
    finite = True
    for k in range(3):
        lo[k] = x[0, k]
        hi[k] = x[0, k]
    for i in range(x.shape[0]):
        for k in range(3):
            v = x[i, k]
            if not math.isfinite(v):
                finite = False
            if v < lo[k]:
                lo[k] = v
            if v > hi[k]:
                hi[k] = v
    return lo, hi, finite


@numba.njit(cache=True, inline="always")
def cell_floor(p, lo, inv_h):
    """Unclamped cell coordinate ``floor((p - lo) * inv_h)`` of the coordinate ``p``."""
    return int(math.floor((p - lo) * inv_h))


@numba.njit(cache=True, inline="always")
def cell_index(p, lo, inv_h, n):
    """Cell coordinate of ``p`` clamped to [0, n - 1] (clamped as a float first, so that a far
    point cannot overflow the integer)."""
    s = (p - lo) * inv_h
    if s > n - 1.0:
        s = n - 1.0
    if s < 0.0:
        s = 0.0
    return int(math.floor(s))


@numba.njit(cache=True, inline="always")
def cell_id(ix, iy, iz, ny, nz):
    """Linear id of cell (ix, iy, iz) in a grid of ny x nz cells per x slab."""
    return (ix * ny + iy) * nz + iz


@numba.njit(cache=True, inline="always")
def forward_column(q):
    """Offset (dx, dy) of forward column q = 1..4 of the half stencil: (0, 1), then (1, -1),
    (1, 0), (1, 1). In cell-id order each column's cells iz - 1 .. iz + 1 are contiguous."""
    if q == 1:
        return 0, 1
    return 1, q - 3


@numba.njit(cache=True, parallel=True)
def cell_ids(x, lo, inv_h, nx, ny, nz):
    """Linear cell id (int64 (N,)) of every point of ``x`` in an nx x ny x nz grid."""
    n = x.shape[0]
    ids = np.empty(n, dtype=np.int64)
    for i in numba.prange(n):
        ix = cell_index(x[i, 0], lo[0], inv_h, nx)
        iy = cell_index(x[i, 1], lo[1], inv_h, ny)
        iz = cell_index(x[i, 2], lo[2], inv_h, nz)
        ids[i] = cell_id(ix, iy, iz, ny, nz)
    return ids


@numba.njit(cache=True, parallel=True)
def cell_coords(x, lo, inv_h, dims):
    """Cell coordinates (int64 (N, 3)) of every point of ``x`` in a grid of ``dims`` cells."""
    n = x.shape[0]
    ijk = np.empty((n, 3), dtype=np.int64)
    for i in numba.prange(n):
        for k in range(3):
            ijk[i, k] = cell_index(x[i, k], lo[k], inv_h, dims[k])
    return ijk


@numba.njit(cache=True)
def counting_sort(ids, ncells, start, perm):
    """Stable O(N + ncells) sort of the cell ids ``ids`` (all in [0, ncells)).

    Writes ``perm`` (N,), the points in cell order (points of one cell keep their order), and
    ``start`` (ncells + 1,), the CSR offsets: cell c holds ``perm[start[c]:start[c + 1]]``.
    """
    start[:] = 0
    for i in range(ids.shape[0]):
        start[ids[i] + 1] += 1
    for c in range(ncells):
        start[c + 1] += start[c]
    for i in range(ids.shape[0]):
        c = ids[i]
        perm[start[c]] = i
        start[c] += 1
    for c in range(ncells, 0, -1):
        start[c] = start[c - 1]
    start[0] = 0


def members(ids: np.ndarray, n: int) -> list[np.ndarray]:
    """For each id in [0, n), the indices (ascending) of the entries of ``ids`` equal to it
    (:func:`counting_sort`)."""
    ids = np.ascontiguousarray(ids, dtype=np.int64)
    start, perm = np.empty(n + 1, dtype=np.int64), np.empty(len(ids), dtype=np.int64)
    counting_sort(ids, n, start, perm)
    return [perm[start[c]:start[c + 1]] for c in range(n)]


@numba.njit(cache=True)
def run_starts(sorted_ids):
    """Start of every run of equal ids in ``sorted_ids`` (the occupied cells), plus the end:
    (M+1,) int64."""
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


@numba.njit(cache=True)
def bin_boxes(lo, hi, dims, start, items):
    """CSR of cell -> items for items covering boxes of cells: item f is entered in every cell
    (i, j, k) with ``lo[f] <= (i, j, k) <= hi[f]``, items in increasing index in each cell.

    ``start`` (ncells + 1,) int64 zeros on entry; ``items`` sized to the total count
    (``prod(hi - lo + 1)`` summed over the items).
    """
    ny = dims[1]
    nz = dims[2]
    for f in range(lo.shape[0]):
        for i in range(lo[f, 0], hi[f, 0] + 1):
            for j in range(lo[f, 1], hi[f, 1] + 1):
                for k in range(lo[f, 2], hi[f, 2] + 1):
                    start[cell_id(i, j, k, ny, nz) + 1] += 1
    for c in range(start.shape[0] - 1):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    for f in range(lo.shape[0]):
        for i in range(lo[f, 0], hi[f, 0] + 1):
            for j in range(lo[f, 1], hi[f, 1] + 1):
                for k in range(lo[f, 2], hi[f, 2] + 1):
                    c = cell_id(i, j, k, ny, nz)
                    items[fill[c]] = f
                    fill[c] += 1


@numba.njit(cache=True)
def in_box(y, lo, hi):
    """Indices (int64, ascending) of the points of ``y`` (N, 3) inside the box [lo, hi] (bounds
    included): a rank's particles near another's box, the particles near a contact surface."""
    out = np.empty(y.shape[0], dtype=np.int64)
    n = 0
    for i in range(y.shape[0]):
        if (lo[0] <= y[i, 0] <= hi[0] and lo[1] <= y[i, 1] <= hi[1]
                and lo[2] <= y[i, 2] <= hi[2]):
            out[n] = i
            n += 1
    return out[:n]
