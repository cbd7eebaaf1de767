"""Neighbour search: the cell (link-list) search against brute force and scipy's cKDTree.

References: the O(N^2) brute-force search (every pair tested), scipy's cKDTree, and for the
lattice the number of integer vectors v with 0 < |v| <= 3.015, counted by enumeration (122).
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from pdfem.pd.bonds.search import (brute_pairs, cell_pairs, cell_sort, ckdtree_pairs, pairs_to_array,
                             search_cell_size)


def canonical(row_ptr, nbr, perm=None) -> np.ndarray:
    """Pairs as a lexicographically sorted (P,2) array of (i < j) in the original numbering."""
    p = pairs_to_array(row_ptr, nbr)
    if perm is not None:
        p = perm[p]
    p.sort(axis=1)
    return p[np.lexsort((p[:, 1], p[:, 0]))]


def check_csr(row_ptr, nbr, n):
    """CSR invariants: offsets monotone from 0 to P, first < second, ascending within a row."""
    assert row_ptr.dtype == np.int64 and nbr.dtype == np.int32
    assert row_ptr.shape == (n + 1,)
    assert row_ptr[0] == 0 and row_ptr[-1] == nbr.shape[0]
    assert np.all(np.diff(row_ptr) >= 0)
    first = np.repeat(np.arange(n), np.diff(row_ptr))
    assert np.all(first < nbr)
    same_row = first[1:] == first[:-1]
    assert np.all(nbr[1:][same_row] > nbr[:-1][same_row])


def all_three(x, delta):
    """Run the three searches, check their CSR invariants and that the pair sets are identical."""
    x = np.asarray(x, dtype=np.float64)
    n = x.shape[0]
    perm, rp_c, nb_c = cell_pairs(x, delta)
    assert perm.dtype == np.int64 and np.array_equal(np.sort(perm), np.arange(n))
    rp_b, nb_b = brute_pairs(x, delta)
    rp_k, nb_k = ckdtree_pairs(x, delta)
    for rp, nb in ((rp_c, nb_c), (rp_b, nb_b), (rp_k, nb_k)):
        check_csr(rp, nb, n)
    ref = canonical(rp_b, nb_b)
    # brute force is already canonical: CSR order is lexicographic order
    assert np.array_equal(ref, pairs_to_array(rp_b, nb_b))
    assert np.array_equal(canonical(rp_c, nb_c, perm), ref)
    assert np.array_equal(rp_k, rp_b) and np.array_equal(nb_k, nb_b)
    # the distance test, independently: every listed pair is within delta, every other is not
    if 0 < n <= 400:
        d2 = ((x[:, None, :] - x[None, :, :]) ** 2).sum(-1)
        i, j = np.nonzero(np.triu(d2 <= delta * delta, k=1))
        assert np.array_equal(np.c_[i, j], ref)
    return perm, rp_c, nb_c, ref


def test_lattice_family_of_interior_particle_is_122():
    """Cubic lattice, delta = 3.015 dx: an interior particle has the 122 integer vectors |v| <= 3.015."""
    r = range(-4, 5)
    n_ref = sum(1 for v in itertools.product(r, r, r) if 0 < v[0] ** 2 + v[1] ** 2 + v[2] ** 2 <= 3.015 ** 2)
    assert n_ref == 122
    dx = 0.1
    side = 11
    g = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3)
    x = (g + 0.5) * dx - 0.3  # some negative coordinates too
    _, _, _, ref = all_three(x, 3.015 * dx)
    family = np.bincount(ref.ravel(), minlength=x.shape[0])
    interior = np.all((g >= 3) & (g <= side - 4), axis=1)
    assert interior.sum() == 125
    assert np.all(family[interior] == 122)
    assert np.all(family[~interior] < 122)


def test_lattice_with_pairs_exactly_at_the_horizon():
    """delta = 3 dx: lattice pairs at exactly delta (up to rounding) decide the same in every search."""
    dx = 0.1
    g = np.stack(np.meshgrid(*[np.arange(9)] * 3, indexing="ij"), -1).reshape(-1, 3)
    all_three(g * dx + 0.05, 3 * dx)
    all_three(g * 1.0, 3.0)  # exact arithmetic: pairs at distance 3 are in


def test_inclusive_distance_test():
    """|x_i - x_j| == delta exactly is a pair; a hair beyond is not."""
    x = np.array([[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [0.0, 1.5 + 1e-12, 0.0]])
    _, _, _, ref = all_three(x, 1.5)
    assert ref.tolist() == [[0, 1]]


@pytest.mark.parametrize("seed, n, delta", [(0, 300, 0.08), (1, 2000, 0.15), (2, 1000, 0.3), (3, 50, 5.0)])
def test_random_uniform_clouds(seed, n, delta):
    """Uniform random points in the unit cube (the last case: everything in one cell) vs brute force."""
    x = np.random.default_rng(seed).random((n, 3))
    all_three(x, delta)


def test_random_flat_clouds():
    """Points on a plane (z = const, then x = const): a grid one cell thick."""
    rng = np.random.default_rng(4)
    x = np.c_[rng.random((1500, 2)) * 3.0, np.full(1500, 0.7)]
    all_three(x, 0.12)
    all_three(x[:, [2, 0, 1]], 0.12)


def test_negative_coordinates():
    """A cloud far on the negative side of every axis."""
    x = np.random.default_rng(5).random((1200, 3)) * [2.0, 1.0, 0.5] - [1000.0, 250.0, 3.0]
    all_three(x, 0.1)


def test_sparse_grid_uses_argsort_path():
    """Few points spread over a huge grid (more cells than the counting sort takes)."""
    rng = np.random.default_rng(6)
    centres = rng.random((60, 3)) * 1000.0
    x = np.concatenate([centres + rng.normal(scale=0.4, size=centres.shape) for _ in range(4)])
    _, _, _, ref = all_three(x, 1.0)
    assert ref.shape[0] > 0


def test_duplicated_points_are_pairs():
    """Points repeated three times: each copy pairs with the other two (distance 0)."""
    base = np.random.default_rng(7).random((40, 3)) * 10.0
    x = np.repeat(base, 3, axis=0)
    _, _, _, ref = all_three(x, 1e-6)
    assert ref.shape[0] == 40 * 3
    assert np.all(ref[:, 1] - ref[:, 0] <= 2) and np.all(ref[:, 0] // 3 == ref[:, 1] // 3)


def test_empty_and_single_particle():
    """N = 0 and N = 1 give no pairs and well-formed arrays."""
    for n in (0, 1):
        x = np.zeros((n, 3))
        perm, rp, nb = cell_pairs(x, 1.0)
        assert perm.shape == (n,) and rp.tolist() == [0] * (n + 1) and nb.shape == (0,)
        for rp, nb in (brute_pairs(x, 1.0), ckdtree_pairs(x, 1.0)):
            assert rp.tolist() == [0] * (n + 1) and nb.shape == (0,)
            check_csr(rp, nb, n)
    assert cell_sort(np.zeros((0, 3)), 1.0).shape == (0,)


def test_cell_sort_orders_by_linear_cell_index_stably():
    """cell_sort against numpy's stable argsort of c = (ix*ny + iy)*nz + iz."""
    rng = np.random.default_rng(8)
    x = np.round(rng.random((3000, 3)) * [5.0, 3.0, 2.0], 1) - 1.0  # many ties within a cell
    h = 0.7
    lo = x.min(axis=0)
    idx = np.floor((x - lo) * (1.0 / h)).astype(np.int64)
    dims = idx.max(axis=0) + 1
    c = (idx[:, 0] * dims[1] + idx[:, 1]) * dims[2] + idx[:, 2]
    assert np.array_equal(cell_sort(x, h), np.argsort(c, kind="stable"))


def test_cell_pairs_numbering_is_the_cell_order():
    """cell_pairs' perm is cell_sort with its cell size (delta enlarged by ~1e-9)."""
    x = np.random.default_rng(9).random((800, 3))
    delta = 0.2
    h = search_cell_size(x, delta)
    assert delta < h < delta * (1 + 1e-8)
    perm, _, _ = cell_pairs(x, delta)
    assert np.array_equal(perm, cell_sort(x, h))


def test_bad_arguments():
    """Non-positive horizons and wrongly shaped positions are refused."""
    x = np.zeros((3, 3))
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError):
            cell_pairs(x, bad)
        with pytest.raises(ValueError):
            cell_sort(x, bad)
    with pytest.raises(ValueError):
        cell_pairs(np.zeros((3, 2)), 1.0)
    with pytest.raises(ValueError):
        brute_pairs(np.array([[0.0, 0.0, np.nan]]), 1.0)


def test_pairs_to_array():
    """CSR expansion: rows repeated by their counts."""
    rp = np.array([0, 2, 2, 3], dtype=np.int64)
    nb = np.array([1, 2, 2], dtype=np.int32)
    assert pairs_to_array(rp, nb).tolist() == [[0, 1], [0, 2], [2, 2]]
