"""Set-up of a lattice-filled ice body: each process builds only its part (all of it on one).

The global set-up (:func:`pdfem.pd.layout.split.split_body` of a whole
:class:`~pdfem.pd.body.IceBody`) builds the whole body on every rank and keeps its part, so
memory per rank does not fall with the rank count. Here each rank, with no global particle or
bond array:

1. counts the shape's lattice plane by plane (:func:`pdfem.pd.layout.census.lattice_census`)
   and cuts the lattice into a grid of boxes balanced by those counts
   (:mod:`pdfem.parallel.box_partition`): the owner of a particle is a function of its lattice
   indices;
2. generates the lattice points of its box plus a band of ``floor(delta/dx) + 1`` planes,
   widened to whole cells of the serial search grid, and gives each its serial (cell-order)
   global number (:func:`pdfem.pd.layout.census.cell_offsets`);
3. finds the bonds among them (:func:`pdfem.pd.bonds.search.cell_pairs`) and keeps those with an
   owned end, as unique pairs i < j in global numbering, sorted as the serial list is: the
   local pair list is the serial one restricted to the local particles, in the same order;
4. weighs the bonds (:func:`pdfem.pd.bonds.influence.bond_weights`, per bond), applies the surface
   correction with the halo's correction tensors exchanged from their owners after every
   iteration (:func:`pdfem.pd.bonds.surface.surface_corrected_weights`), and computes the
   weighted volume m of its owned particles, the halo's m exchanged from their owners.

Every owned particle sees its whole family in the serial order, and the pair loops sum over
blocks fixed by the whole body (:mod:`pdfem.pd.layout.blocks`), so the local arrays are the
whole body's local arrays exactly, on any number of ranks and threads. On one process this is
the whole body (:meth:`IceBody.from_shape <pdfem.pd.body.IceBody.from_shape>`). Units: SI.
"""

from __future__ import annotations

import numba
import numpy as np

from pdfem.geometry.lattice import lattice_plane
from pdfem.parallel.box_partition import BoxPartition, choose_box_partition
from pdfem.pd.bonds import kernels
from pdfem.pd.bonds.geometry import bond_lengths
from pdfem.pd.bonds.data import Bonds
from pdfem.pd.layout.blocks import layout_workspace
from pdfem.pd.layout.halo import HaloPlan, make_layout
from pdfem.pd.layout.census import cell_offsets, halo_planes, lattice_census, plane_mask
from pdfem.pd.bonds.surface import surface_corrected_weights
from pdfem.pd.bonds.influence import bond_weights, isotropy_gain
from pdfem.pd.bonds.search import cell_pairs


def _grow(a: int, b: int, h: int, cells: np.ndarray) -> tuple[int, int]:
    """The plane range ``[a, b)`` grown by ``h`` planes each side, then to whole cells."""
    n = len(cells)
    a, b = max(0, a - h), min(n, b + h)
    while a > 0 and cells[a - 1] == cells[a]:
        a -= 1
    while b < n and cells[b] == cells[b - 1]:
        b += 1
    return a, b


def candidates(shape, census, part: BoxPartition, rank: int, h: int):
    """The lattice points (m) of ``rank``'s box grown by ``h`` planes (and to whole cells), in
    global (serial) order, with their global numbers and lattice indices."""
    blo, bhi = part.box(rank)
    cop = census.cell_of_plane
    rng = [_grow(int(blo[k]), int(bhi[k]), h, cop[k]) for k in range(3)]
    nyl, nzl = len(census.axes[1]), len(census.axes[2])
    jj, kk = np.meshgrid(np.arange(*rng[1]), np.arange(*rng[2]), indexing="ij")
    jj, kk = jj.reshape(-1), kk.reshape(-1)
    pts, ijk = [], []
    for i in range(*rng[0]):
        p = lattice_plane(census.axes, i, rng[1], rng[2])
        m = plane_mask(shape, p)
        if m.any():
            pts.append(p[m])
            ijk.append(np.stack([np.full(int(m.sum()), i), jj[m], kk[m]], axis=1))
    x = np.concatenate(pts) if pts else np.zeros((0, 3))
    ijk = np.concatenate(ijk).astype(np.int64) if ijk else np.zeros((0, 3), np.int64)
    _, nyc, nzc = census.dims
    cell = (cop[0][ijk[:, 0]] * nyc + cop[1][ijk[:, 1]]) * nzc + cop[2][ijk[:, 2]]
    lat = (ijk[:, 0] * nyl + ijk[:, 1]) * nzl + ijk[:, 2]
    order = np.lexsort((lat, cell))
    x, ijk, cell = np.ascontiguousarray(x[order]), ijk[order], cell[order]
    # rank in lattice order within the cell (whole cells are present) + the cell's first number
    new = np.concatenate([[True], cell[1:] != cell[:-1]])
    start = np.maximum.accumulate(np.where(new, np.arange(len(cell)), 0))
    s0 = int(cop[0][rng[0][0]])
    first = cell_offsets(shape, census, (s0, int(cop[0][rng[0][1] - 1]) + 1))
    slab, yz = np.divmod(cell, nyc * nzc)
    gid = first[slab - s0, yz] + (np.arange(len(cell)) - start)
    return x, gid, ijk


@numba.njit(cache=True)
def _kept_pairs(perm, row_ptr, nbr, owned):
    """The pairs of a search (in its cell numbering ``perm``) with an owned end, as CSR rows
    i < j in the candidates' (global) order, each row ascending."""
    n = perm.shape[0]
    ptr = np.zeros(n + 1, dtype=np.int64)
    for r in range(n):
        a = perm[r]
        for k in range(row_ptr[r], row_ptr[r + 1]):
            b = perm[nbr[k]]
            if owned[a] or owned[b]:
                ptr[min(a, b) + 1] += 1
    for i in range(n):
        ptr[i + 1] += ptr[i]
    out = np.empty(ptr[n], dtype=np.int32)
    fill = ptr[:n].copy()
    for r in range(n):
        a = perm[r]
        for k in range(row_ptr[r], row_ptr[r + 1]):
            b = perm[nbr[k]]
            if owned[a] or owned[b]:
                lo = min(a, b)
                out[fill[lo]] = max(a, b)
                fill[lo] += 1
    for i in range(n):
        out[ptr[i]:ptr[i + 1]].sort()
    return ptr, out


def local_pairs(x: np.ndarray, owned: np.ndarray, delta: float):
    """Local particles (mask over the candidates) and their pair list (CSR, local numbering)."""
    perm, row_ptr, nbr = cell_pairs(x, delta)
    ptr, out = _kept_pairs(perm, row_ptr, nbr, owned.astype(np.uint8))
    del perm, row_ptr, nbr
    keep = owned.copy()
    keep[out] = True
    keep |= np.diff(ptr) > 0
    new = (np.cumsum(keep) - 1).astype(np.int32)
    row = np.concatenate([[0], np.cumsum(np.diff(ptr)[keep])]).astype(np.int64)
    return keep, row, new[out]  # int32 (4 B per bond, no int64 temporary)


def local_plan(gid, owned, owner, row_ptr, nbr, rank: int) -> HaloPlan:
    """The :class:`~pdfem.pd.layout.halo.HaloPlan` of the local particles (``pairs`` None: no
    global bond numbers; checkpoints name bonds by their ends, :mod:`pdfem.pd.checkpoint.parts`)."""
    recv, send = {}, {}
    for q in np.unique(owner[~owned]):
        q = int(q)
        recv[q] = np.flatnonzero(~owned & (owner == q))
        send[q] = np.flatnonzero(_bonded_to(row_ptr, nbr, owned, owner, q))
    return HaloPlan(gid, owned, None, send, recv)


@numba.njit(cache=True)
def _bonded_to(row_ptr, nbr, owned, owner, q):
    """Which owned particles have a bond partner owned by rank ``q`` (what ``q`` needs)."""
    mark = np.zeros(row_ptr.shape[0] - 1, dtype=np.bool_)
    for i in range(row_ptr.shape[0] - 1):
        for k in range(row_ptr[i], row_ptr[i + 1]):
            j = nbr[k]
            if owned[i] and owner[j] == q:
                mark[i] = True
            if owned[j] and owner[i] == q:
                mark[j] = True
    return mark


def setup_partition(shape, dx: float, delta: float, n_parts: int):
    """The census of ``shape`` and its box partition over ``n_parts`` ranks."""
    census = lattice_census(shape, dx, delta)
    return census, choose_box_partition(census.marginals, n_parts, halo_planes(delta, dx) - 1)


def lattice_part(shape, dx: float, delta: float, comm, *, isotropic: bool = True,
                 surface_correction: bool = True, census=None,
                 part: BoxPartition | None = None) -> dict:
    """This process's part of the body filling ``shape`` with a cubic lattice of spacing
    ``dx`` and horizon ``delta`` (m), built without the whole body (the whole body on one
    process). Collective.

    Parameters
    ----------
    shape
        A :mod:`pdfem.geometry.shapes` object.
    dx, delta
        Lattice spacing and horizon (m).
    comm
        The communicator.
    isotropic
        Weigh the bonds with the cubic influence function (:func:`pdfem.pd.bonds.influence.
        isotropy_gain`); False: w = 1.
    surface_correction
        Correct the weights near free surfaces (:mod:`pdfem.pd.bonds.surface`).
    census, part
        The lattice census and box partition, if already made (:func:`setup_partition`).

    Returns
    -------
    dict
        The geometric arguments of :class:`~pdfem.pd.body.IceBody`: ``x0`` (m), ``vol``
        (m^3), ``bonds``, ``m`` (m^5), ``layout`` (a :class:`~pdfem.pd.layout.base.WholeLayout`
        on one process, else a :class:`~pdfem.pd.layout.halo.HaloLayout`) and
        ``influence_gain``.
    """
    if census is None or part is None:
        census, part = setup_partition(shape, dx, delta, comm.size)
    gain = isotropy_gain(delta / dx) if isotropic else 0.0
    x, gid, ijk = candidates(shape, census, part, comm.rank, halo_planes(delta, dx))
    owner = part.owner(ijk)
    del ijk
    keep, row_ptr, nbr = local_pairs(x, owner == comm.rank, delta)
    x, gid, owner = np.ascontiguousarray(x[keep]), gid[keep], owner[keep]
    owned = owner == comm.rank
    plan = local_plan(gid, owned, owner, row_ptr, nbr, comm.rank)
    n = len(gid)
    vol = np.full(n, dx ** 3)
    xi_len = bond_lengths(x, row_ptr, nbr)
    weight = bond_weights(x, row_ptr, nbr, xi_len, float(delta), float(dx), gain)
    layout = make_layout(comm, plan, census.n, f"{part.name} (distributed set-up)")
    ws = layout_workspace(row_ptr, nbr, layout, keep_bond_length=False)
    if surface_correction:
        surface_corrected_weights(x, row_ptr, nbr, xi_len, weight, vol, ws=ws, out=weight,
                                  exchange=layout.exchange)
    m = kernels.weighted_volume(row_ptr, nbr, xi_len, weight, vol, ws)
    layout.exchange(m)
    layout.exchange_seconds = 0.0
    return {"x0": x, "vol": vol, "bonds": Bonds(row_ptr, nbr, xi_len, weight), "m": m,
            "layout": layout, "influence_gain": gain}
