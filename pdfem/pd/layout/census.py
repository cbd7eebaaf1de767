"""Counts of a lattice-filled shape computed plane by plane: nothing global-sized is held.

The distributed set-up (:mod:`pdfem.pd.layout.setup`) must reproduce the serial body's
particle numbering without the global particle array. The serial body (:meth:`IceBody.from_points
<pdfem.pd.body.IceBody.from_points>`) fills the shape in lattice order (x-major, z fastest,
:func:`pdfem.geometry.lattice.fill`) and then renumbers the particles in *cell order*: by the
cell of the search grid (side about delta, anchored at the minimum corner of the particles'
bounding box, :mod:`pdfem.pd.bonds.search`) that holds them, stable, so lattice order within a cell.
A particle's global number is therefore

    (particles in the cells of smaller linear cell id) + (its rank in lattice order in its cell).

:func:`lattice_census` walks the lattice one x plane at a time (evaluating the shape test per
point) and returns the per-plane marginal counts along each axis and the bounding box of the
particles, hence the search grid; :func:`cell_offsets` walks it again and returns the
particles per cell slab (all slabs) and the per-cell counts of the few slabs a rank needs, from
which the first global number of each of its cells follows. Memory: one lattice plane at a time
plus the counts of the needed slabs (about N / 27 cells for the whole body, a fraction of that
per rank). Positions in m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pdfem.geometry.cell_hash import cell_coords
from pdfem.geometry.lattice import lattice_axes, lattice_plane
from pdfem.pd.bonds.search import box_cell_size, grid_dims


@dataclass
class LatticeCensus:
    """What every rank knows of a lattice-filled shape before any particle exists.

    Attributes
    ----------
    axes
        The lattice plane coordinates (m) along x, y, z.
    marginals
        Particles per lattice plane along x, y and z (int64).
    n
        Number of particles of the body.
    lo, hi
        (3,) bounding box of the particles (m), as :func:`pdfem.geometry.cell_hash.bounding_box`.
    dims
        Cells per axis of the serial search grid.
    cell_of_plane
        Per axis, the search-grid cell coordinate of each lattice plane (int64).
    """

    axes: list
    marginals: list
    n: int
    lo: np.ndarray
    hi: np.ndarray
    dims: tuple
    cell_of_plane: list


def plane_mask(shape, pts: np.ndarray) -> np.ndarray:
    """Which points of one lattice plane lie in ``shape`` (all for a shape that fills its box)."""
    if shape.fills_bounds:
        return np.ones(len(pts), dtype=bool)
    return np.asarray(shape.contains(pts), dtype=bool)


def lattice_census(shape, dx: float, delta: float) -> LatticeCensus:
    """Count the particles of ``shape`` filled at spacing ``dx`` (m) per lattice plane and find
    the serial search grid of horizon ``delta`` (m), one x plane at a time.

    Raises
    ------
    ValueError
        If the shape holds no particle, or its search grid would need renumbering (more than
        2**62 cells; the global set-up handles that case).
    """
    lo_s, hi_s = shape.bounds()
    axes = lattice_axes(lo_s, hi_s, dx)
    nx, ny, nz = (len(a) for a in axes)
    marg = [np.zeros(nx, np.int64), np.zeros(ny, np.int64), np.zeros(nz, np.int64)]
    for i in range(nx):
        m = plane_mask(shape, lattice_plane(axes, i)).reshape(ny, nz)
        c = int(m.sum())
        marg[0][i] = c
        if c:
            marg[1] += m.sum(axis=1)
            marg[2] += m.sum(axis=0)
    n = int(marg[0].sum())
    if n == 0:
        raise ValueError("the shape holds no lattice point at this spacing")
    first = [int(np.flatnonzero(mk)[0]) for mk in marg]
    last = [int(np.flatnonzero(mk)[-1]) for mk in marg]
    lo = np.array([axes[k][first[k]] for k in range(3)])
    hi = np.array([axes[k][last[k]] for k in range(3)])
    cell = box_cell_size(lo, hi, float(delta))
    dims = grid_dims(lo, hi, cell)
    if float(dims[0]) * dims[1] * dims[2] > 2.0 ** 62:
        raise ValueError("the search grid of this body has more than 2**62 cells")
    inv_h = 1.0 / cell
    dims_arr = np.asarray(dims, dtype=np.int64)
    cop = []
    for k in range(3):
        p = np.repeat(lo[None, :], len(axes[k]), axis=0)
        p[:, k] = axes[k]
        cop.append(np.ascontiguousarray(cell_coords(p, lo, inv_h, dims_arr)[:, k]))
    return LatticeCensus(axes, marg, n, lo, hi, tuple(int(d) for d in dims), cop)


def cell_offsets(shape, census: LatticeCensus, slabs: tuple[int, int]) -> np.ndarray:
    """First global particle number of every cell of the cell slabs ``slabs[0]:slabs[1]``
    (along x), as an int64 array (slabs, ny * nz cells), one lattice plane at a time."""
    axes, cop = census.axes, census.cell_of_plane
    nxc, nyc, nzc = census.dims
    s0, s1 = slabs
    per_slab = np.zeros(nxc, dtype=np.int64)
    cells = np.zeros((s1 - s0, nyc * nzc), dtype=np.int64)
    yz = (cop[1][:, None] * nzc + cop[2][None, :]).reshape(-1)
    for i in range(len(axes[0])):
        if census.marginals[0][i] == 0:
            continue
        ix = int(cop[0][i])
        m = plane_mask(shape, lattice_plane(axes, i))
        per_slab[ix] += int(m.sum())
        if s0 <= ix < s1:
            cells[ix - s0] += np.bincount(yz[m], minlength=nyc * nzc)
    start = np.concatenate([[0], np.cumsum(per_slab)])
    first = np.cumsum(cells, axis=1) - cells
    return first + start[s0:s1, None]


def halo_planes(delta: float, dx: float) -> int:
    """Lattice planes a bond of horizon ``delta`` can cross (floor(delta / dx)), plus one for
    rounding."""
    return int(math.floor(delta / dx)) + 1
