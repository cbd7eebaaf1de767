"""Benchmark of the neighbour search: pdfem's cell search against scipy's cKDTree (and brute force).

A cubic lattice of about ``n`` particles (``round(n ** (1/3))`` per axis, dx = 1 m) and a horizon
of ``horizon_factor`` dx. Each search is timed from positions to the canonical CSR pair list
(everything a caller waits for): for :func:`~pdfem.pd.bonds.search.cell_pairs` the cell sort and the
search, for :func:`~pdfem.pd.bonds.search.ckdtree_pairs` the tree build, the query and the conversion
to CSR. Times are the best of ``repeat`` runs (``time.perf_counter``), after a warm-up on a tiny
lattice that compiles (or loads) the numba kernels. The pair sets are checked to agree: same
number of pairs and the same family size for every particle.

Run it with ``pdfem bench search`` or
``python -c "from pdfem.benchmarks.search import bench_search; print(bench_search())"``.
"""

from __future__ import annotations

import gc
import time

import numba
import numpy as np

from pdfem.geometry.lattice import lattice_points
from pdfem.pd.bonds.search import brute_pairs, cell_pairs, ckdtree_pairs


def _best_of(repeat: int, fn, *args):
    """Best wall time (s) of ``repeat`` calls and the result of the last one."""
    best = float("inf")
    out = None
    for _ in range(max(1, repeat)):
        out = None
        gc.collect()
        t0 = time.perf_counter()
        out = fn(*args)
        best = min(best, time.perf_counter() - t0)
    return best, out


def _family_sizes(n: int, row_ptr: np.ndarray, nbr: np.ndarray, perm: np.ndarray | None = None) -> np.ndarray:
    """Number of partners of every particle (both ends of each pair), in the original numbering."""
    first = np.repeat(np.arange(n, dtype=np.int64), np.diff(row_ptr))
    second = nbr.astype(np.int64)
    if perm is not None:
        first = perm[first]
        second = perm[second]
    return np.bincount(first, minlength=n) + np.bincount(second, minlength=n)


def bench_search(n: int = 1_000_000, horizon_factor: float = 3.015, brute_max: int = 100_000,
                 repeat: int = 3) -> dict:
    """Time the cell search, cKDTree and (for small ``n``) brute force on a cubic lattice.

    Parameters
    ----------
    n
        Approximate number of particles; the lattice has ``round(n ** (1/3))`` points per axis.
    horizon_factor
        Horizon over lattice spacing (dx = 1 m, so delta = horizon_factor m).
    brute_max
        Brute force is timed only when the particle count is at most this.
    repeat
        Each search is run this many times; the best time is reported.

    Returns
    -------
    dict
        ``n_particles``, ``n_pairs``, ``delta`` (m), ``threads``, ``cell_s``, ``ckdtree_s``,
        ``speedup_vs_ckdtree``, ``brute_s`` (only when measured), ``pairs_per_particle``,
        ``cell_pairs_per_s``.

    Raises
    ------
    RuntimeError
        If the searches disagree.
    """
    side = max(2, int(round(n ** (1.0 / 3.0))))
    dx = 1.0
    delta = float(horizon_factor) * dx
    x = lattice_points(np.zeros(3), np.full(3, side * dx), dx)
    n_particles = x.shape[0]

    # warm-up: compile or load every kernel (not timed)
    tiny = lattice_points(np.zeros(3), np.full(3, 6 * dx), dx)
    cell_pairs(tiny, delta)
    ckdtree_pairs(tiny, delta)
    brute_pairs(tiny, delta)

    cell_s, (perm, row_ptr, nbr) = _best_of(repeat, cell_pairs, x, delta)
    n_pairs = int(nbr.shape[0])
    fam_cell = _family_sizes(n_particles, row_ptr, nbr, perm)
    del perm, row_ptr, nbr

    ckdtree_s, (row_ptr, nbr) = _best_of(repeat, ckdtree_pairs, x, delta)
    if nbr.shape[0] != n_pairs or not np.array_equal(_family_sizes(n_particles, row_ptr, nbr), fam_cell):
        raise RuntimeError(f"cell search and cKDTree disagree: {n_pairs} against {nbr.shape[0]} pairs")
    del row_ptr, nbr

    result = {
        "n_particles": int(n_particles),
        "n_pairs": n_pairs,
        "delta": delta,
        "threads": int(numba.get_num_threads()),
        "cell_s": cell_s,
        "ckdtree_s": ckdtree_s,
        "speedup_vs_ckdtree": ckdtree_s / cell_s,
    }
    if n_particles <= brute_max:
        brute_s, (row_ptr, nbr) = _best_of(repeat, brute_pairs, x, delta)
        if nbr.shape[0] != n_pairs or not np.array_equal(_family_sizes(n_particles, row_ptr, nbr), fam_cell):
            raise RuntimeError(f"cell search and brute force disagree: {n_pairs} against "
                               f"{nbr.shape[0]} pairs")
        result["brute_s"] = brute_s
        result["speedup_vs_brute"] = brute_s / cell_s
    result["pairs_per_particle"] = n_pairs / n_particles
    result["cell_pairs_per_s"] = n_pairs / cell_s
    return result
