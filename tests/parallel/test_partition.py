"""Domain partitions for MPI (pdfem.parallel.partition): balance and exact halo counts.

References: a brute-force count of halos and neighbours from the pair list with Python sets,
and the geometry of a thin plate (a plate must be cut across its plane, never through its
thickness, to keep halos small).
"""

from __future__ import annotations

import numpy as np
import pytest

from pdfem.parallel.partition import (choose_partition, grid_partition, grid_shapes,
                                      partition_stats, rcb_partition)
from pdfem.geometry.lattice import fill
from pdfem.pd.bonds.search import cell_pairs
from pdfem.geometry.shapes import Box


def _plate(nx, ny, nz, dx=1.0):
    x = fill(Box((0, 0, 0), (nx * dx, ny * dx, nz * dx)), dx)
    perm, row_ptr, nbr = cell_pairs(x, 3.015 * dx)
    return x[perm], row_ptr, nbr


def _brute(owner, row_ptr, nbr, n_parts):
    halo = [set() for _ in range(n_parts)]
    for i in range(len(row_ptr) - 1):
        for j in nbr[row_ptr[i]:row_ptr[i + 1]]:
            if owner[i] != owner[j]:
                halo[owner[i]].add(int(j))
                halo[owner[j]].add(i)
    neighbours = [len({int(owner[p]) for p in h}) for h in halo]
    return [len(h) for h in halo], neighbours


@pytest.mark.parametrize("n_parts", [1, 2, 3, 4, 6, 7])
def test_partitions_are_balanced_and_stats_match_brute_force(n_parts):
    """Every partitioner gives each rank N / n_parts particles to within one, and the halo
    and neighbour counts equal a brute-force count over the bonds."""
    x, row_ptr, nbr = _plate(14, 10, 3)
    cands = [("rcb", rcb_partition(x, n_parts))]
    cands += [(str(s), grid_partition(x, s)) for s in grid_shapes(n_parts)]
    for name, owner in cands:
        counts = np.bincount(owner, minlength=n_parts)
        assert counts.max() - counts.min() <= 1, name
        st = partition_stats(owner, row_ptr, nbr, n_parts, name)
        halo, neighbours = _brute(owner, row_ptr, nbr, n_parts)
        np.testing.assert_array_equal(st.halo, halo)
        np.testing.assert_array_equal(st.neighbours, neighbours)
        np.testing.assert_array_equal(st.owned, counts)


def test_thin_plate_is_cut_across_its_plane():
    """A plate 40 x 20 x 3 particles on 4 ranks: the chosen partition never cuts through the
    thickness (every rank owns full columns), and it beats cutting the thickness."""
    x, row_ptr, nbr = _plate(40, 20, 3)
    owner, st = choose_partition(x, row_ptr, nbr, 4)
    cols = {}
    for p, o in zip(map(tuple, x[:, :2].round(6)), owner):
        cols.setdefault(p, set()).add(int(o))
    assert all(len(s) == 1 for s in cols.values())
    through = partition_stats(grid_partition(x, (2, 1, 2)), row_ptr, nbr, 4)
    assert st.halo.max() < through.halo.max()
    assert st.imbalance <= 1.0 / st.owned.mean()


def test_grid_shapes_and_bad_input():
    assert sorted(grid_shapes(4)) == [(1, 1, 4), (1, 2, 2), (1, 4, 1), (2, 1, 2), (2, 2, 1),
                                      (4, 1, 1)]
    with pytest.raises(ValueError):
        rcb_partition(np.zeros((3, 3)), 0)
    with pytest.raises(ValueError):
        grid_partition(np.zeros((3, 3)), (0, 1, 1))
