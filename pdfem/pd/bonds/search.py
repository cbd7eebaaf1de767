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

The cells, the counting sort and the half stencil's columns are those of
:mod:`pdfem.geometry.cell_hash`; the numba loops of the search are in
:mod:`pdfem.pd.bonds.search_kernels`. :func:`cell_pairs` is what the builders use;
:func:`brute_pairs` (O(N^2)) and :func:`ckdtree_pairs` (scipy) are references for tests and the
benchmark.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from pdfem.geometry.cell_hash import (
    bounding_box,
    cell_coords,
    cell_ids,
    counting_sort,
    run_starts,
)
from pdfem.pd.bonds.search_kernels import (
    brute,
    count_pass,
    fill_pass,
    gather_soa,
    pairs_to_csr,
    stencil,
)

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


def grid_dims(lo: np.ndarray, hi: np.ndarray, cell_size: float) -> list[int]:
    """Cells per axis of the grid of side ``cell_size`` anchored at ``lo`` that covers ``hi``."""
    inv_h = 1.0 / cell_size
    span = [(hi[k] - lo[k]) * inv_h for k in range(3)]
    if max(span) >= 2.0 ** 52:
        raise ValueError(f"the cell size {cell_size:g} m is too small for the extent of the particles "
                         f"({float(np.max(hi - lo)):g} m): more than 2**52 cells along an axis")
    return [int(math.floor(v)) + 1 for v in span]


def _sort_by_cell(x: np.ndarray, lo: np.ndarray, hi: np.ndarray, cell_size: float):
    """``perm``, the sorted cell ids and the grid dimensions (x checked, N >= 1).

    A grid of more than 2**62 cells (a tiny cell for the extent) is first compressed: along each
    axis the occupied cell coordinates are renumbered 0, 1, 2, ... in order. That keeps the order
    of the cells and the adjacency of occupied ones (cells adjacent before are adjacent after;
    some that were not become so, which only adds candidates that the distance test rejects).
    """
    dims = grid_dims(lo, hi, cell_size)
    inv_h = 1.0 / cell_size
    # cell coordinates from (x - lo) * (1/h): the same monotone expression for every particle
    if float(dims[0]) * dims[1] * dims[2] <= 2.0 ** 62:
        ids = cell_ids(x, lo, inv_h, dims[0], dims[1], dims[2])
    else:
        ijk = cell_coords(x, lo, inv_h, np.asarray(dims, dtype=np.int64))
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
        perm = np.empty(x.shape[0], dtype=np.int64)
        counting_sort(ids, ncells, np.empty(ncells + 1, dtype=np.int64), perm)
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
    lo, hi, _ = bounding_box(x)
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
    lo, hi, _ = bounding_box(x)
    return box_cell_size(lo, hi, delta)


def box_cell_size(lo: np.ndarray, hi: np.ndarray, delta: float) -> float:
    """The search cell side (m) for the box ``lo``..``hi`` and horizon ``delta``: delta made a
    hair larger, so that rounding of the cell coordinates cannot lose a pair at exactly delta."""
    ncell = float(np.max(hi - lo)) / delta
    return delta * (1.0 + 1e-9 + 8e-16 * ncell)


# --------------------------------------------------------------------------------------------
# cell search


def _chunks(work: np.ndarray, nchunk: int) -> np.ndarray:
    """Split the cells into up to ``nchunk`` consecutive runs of about equal work."""
    cum = np.cumsum(work)
    targets = cum[-1] * np.arange(1, nchunk) / nchunk
    inner = np.searchsorted(cum, targets, side="right")
    return np.unique(np.concatenate([[0], inner, [work.shape[0]]])).astype(np.int64)


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
    lo, hi, _ = bounding_box(x)
    perm, sorted_ids, (nx, ny, nz) = _sort_by_cell(x, lo, hi, box_cell_size(lo, hi, delta))
    xs, ys, zs = gather_soa(x, perm)
    first = run_starts(sorted_ids)
    ranges, work = stencil(sorted_ids, first, nx, ny, nz)
    chunks = _chunks(work, 8 * numba.get_num_threads())
    r2 = delta * delta
    # the large outputs are allocated by numpy (which asks the kernel for huge pages)
    row_ptr = np.empty(n + 1, dtype=np.int64)
    row_ptr[0] = 0
    count_pass(xs, ys, zs, first, ranges, chunks, r2, row_ptr[1:])
    np.cumsum(row_ptr[1:], out=row_ptr[1:])
    nbr = np.empty(int(row_ptr[n]), dtype=np.int32)
    if fill_pass(xs, ys, zs, first, ranges, chunks, r2, row_ptr, nbr) != 0:
        raise RuntimeError("cell search: the fill pass disagrees with the count pass (a bug)")
    return perm, row_ptr, nbr


# --------------------------------------------------------------------------------------------
# references


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
    return brute(x, delta * delta)


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
    return pairs_to_csr(x, np.ascontiguousarray(pairs, dtype=np.int64), delta * delta)


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
