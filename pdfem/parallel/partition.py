"""Static domain partitions of an ice body for MPI, and what they cost in communication.

Each particle is owned by one rank for the whole run (bonds only break, so families and hence
the halo pattern never change). A rank needs, besides its own particles, the *halo*: the bond
partners of its particles owned by other ranks; every step it receives their positions and then
their dilatations. The seed paper (Zhang et al. 2023, section 5, Fig. 12) found that the
partition decides the efficiency: the fewest communicating neighbours and equal halo sizes.

Two partitioners are offered, both balanced to within one particle per rank:

* :func:`grid_partition`: a px x py x pz grid; cuts along each axis are placed at quantiles of
  the particle coordinates (x first, then y within each x slab, then z within each column), so
  every rank gets N / (px py pz) particles even on uneven shapes.
* :func:`rcb_partition`: recursive coordinate bisection, each cut across the longest extent of
  the current piece, splitting the particle count in proportion to the ranks on each side (so
  any rank count works, e.g. 3).

:func:`partition_stats` counts, per rank, owned and halo particles and communicating neighbours
from the bond list itself (exact, not a geometric estimate), and :func:`choose_partition` tries
RCB and every grid factorisation and keeps the one with the smallest largest halo, then the
fewest neighbours. Positions in m; communication volume in bytes per step.

No spatial hash here (so none of :mod:`pdfem.geometry.cell_hash`): the halo is selected from the
bond list itself (a rank's halo is exactly the bond partners of its particles owned elsewhere,
:func:`partition_stats`, :func:`pdfem.pd.layout.halo.halo_plan`), which is exact, and the cuts
are quantiles of sorted coordinates. A geometric (cell) selection could only over-approximate
the halo, and the bonds already are the result of the cell search (:mod:`pdfem.pd.bonds.search`).
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import permutations

import numba
import numpy as np

BYTES_PER_HALO_PARTICLE = 8 * (3 + 1)
"""Bytes received per halo particle and step: its position (3 float64), then its dilatation."""


def _balanced_cuts(values: np.ndarray, index: np.ndarray, parts: int) -> list[np.ndarray]:
    """Split ``index`` into ``parts`` groups of (nearly) equal size ordered by ``values[index]``
    (a stable sort, so ties keep the particle order: deterministic)."""
    order = index[np.argsort(values[index], kind="stable")]
    bounds = (np.arange(parts + 1) * len(order)) // parts
    return [order[bounds[k]:bounds[k + 1]] for k in range(parts)]


def grid_partition(x: np.ndarray, shape: tuple[int, int, int]) -> np.ndarray:
    """Owner rank (int32, (N,)) of each particle for a px x py x pz grid partition.

    Parameters
    ----------
    x
        (N, 3) particle positions (m).
    shape
        (px, py, pz) ranks along x, y and z; rank = (i px-slab) * py * pz + j * pz + k.
    """
    px, py, pz = (int(s) for s in shape)
    if min(px, py, pz) < 1:
        raise ValueError(f"grid shape must be positive, got {shape}")
    owner = np.empty(len(x), dtype=np.int32)
    rank = 0
    for slab in _balanced_cuts(x[:, 0], np.arange(len(x)), px):
        for column in _balanced_cuts(x[:, 1], slab, py):
            for cell in _balanced_cuts(x[:, 2], column, pz):
                owner[cell] = rank
                rank += 1
    return owner


def rcb_partition(x: np.ndarray, n_parts: int) -> np.ndarray:
    """Owner rank (int32, (N,)) of each particle by recursive coordinate bisection.

    Each piece is cut across its longest extent; the particle count is split in proportion to
    the ranks given to each side (floor(n/2) and ceil(n/2)).
    """
    if n_parts < 1:
        raise ValueError(f"n_parts must be >= 1, got {n_parts}")
    owner = np.empty(len(x), dtype=np.int32)
    stack = [(np.arange(len(x)), 0, int(n_parts))]
    while stack:
        idx, first, n = stack.pop()
        if n == 1:
            owner[idx] = first
            continue
        pts = x[idx]
        axis = int(np.argmax(pts.max(axis=0) - pts.min(axis=0))) if len(idx) else 0
        order = idx[np.argsort(pts[:, axis], kind="stable")]
        left = n // 2
        cut = (len(order) * left) // n
        stack.append((order[cut:], first + left, n - left))
        stack.append((order[:cut], first, left))
    return owner


@numba.njit(cache=True)
def _halo_keys(owner, row_ptr, nbr, n):
    """Keys rank * n + particle of (rank, halo particle) for every bond crossing ranks."""
    count = 0
    for i in range(row_ptr.shape[0] - 1):
        oi = owner[i]
        for k in range(row_ptr[i], row_ptr[i + 1]):
            if owner[nbr[k]] != oi:
                count += 2
    keys = np.empty(count, dtype=np.int64)
    c = 0
    for i in range(row_ptr.shape[0] - 1):
        oi = owner[i]
        for k in range(row_ptr[i], row_ptr[i + 1]):
            j = nbr[k]
            oj = owner[j]
            if oj != oi:
                keys[c] = np.int64(oi) * n + j
                keys[c + 1] = np.int64(oj) * n + i
                c += 2
    return keys


@dataclass(frozen=True)
class PartitionStats:
    """Per-rank figures of a partition (arrays of length n_parts)."""

    name: str
    owned: np.ndarray        # particles owned
    halo: np.ndarray         # halo particles received every step
    neighbours: np.ndarray   # ranks exchanged with

    @property
    def n_parts(self) -> int:
        return len(self.owned)

    @property
    def imbalance(self) -> float:
        """Largest owned count over the mean, minus 1."""
        return float(self.owned.max() / self.owned.mean() - 1.0)

    @property
    def bytes_per_step(self) -> int:
        """Total bytes sent per step by all ranks (positions and dilatations of the halos)."""
        return int(self.halo.sum()) * BYTES_PER_HALO_PARTICLE

    def summary(self) -> dict:
        """Plain numbers for reports and JSON."""
        return {"partition": self.name, "ranks": self.n_parts,
                "owned_max": int(self.owned.max()), "owned_min": int(self.owned.min()),
                "imbalance": self.imbalance, "halo_max": int(self.halo.max()),
                "halo_mean": float(self.halo.mean()),
                "neighbours_max": int(self.neighbours.max()),
                "bytes_per_step": self.bytes_per_step}


def partition_stats(owner: np.ndarray, row_ptr: np.ndarray, nbr: np.ndarray,
                    n_parts: int, name: str = "") -> PartitionStats:
    """Owned, halo and neighbour counts per rank, from the bond list (exact).

    Parameters
    ----------
    owner
        (N,) owner rank of each particle.
    row_ptr, nbr
        The unique pairs i < j of the body (CSR, :func:`pdfem.pd.bonds.search.cell_pairs`).
    n_parts
        Number of ranks.
    """
    owner = np.ascontiguousarray(owner, dtype=np.int32)
    n = len(owner)
    keys = np.unique(_halo_keys(owner, np.asarray(row_ptr), np.asarray(nbr), n))
    rank, particle = keys // n, keys % n
    halo = np.bincount(rank, minlength=n_parts)
    pairs = np.unique(rank * n_parts + owner[particle])
    neighbours = np.bincount(pairs // n_parts, minlength=n_parts)
    return PartitionStats(name, np.bincount(owner, minlength=n_parts), halo, neighbours)


def grid_shapes(n_parts: int) -> list[tuple[int, int, int]]:
    """Every (px, py, pz) with px py pz = n_parts."""
    out = set()
    for a in range(1, n_parts + 1):
        if n_parts % a:
            continue
        for b in range(1, n_parts // a + 1):
            if (n_parts // a) % b == 0:
                for p in permutations((a, b, n_parts // a // b)):
                    out.add(p)
    return sorted(out)


def candidate_partitions(x: np.ndarray, n_parts: int):
    """(name, owner) of RCB and of every grid shape for ``n_parts`` ranks."""
    yield "rcb", rcb_partition(x, n_parts)
    for shape in grid_shapes(n_parts):
        yield "grid {}x{}x{}".format(*shape), grid_partition(x, shape)


def choose_partition(x: np.ndarray, row_ptr: np.ndarray, nbr: np.ndarray,
                     n_parts: int) -> tuple[np.ndarray, PartitionStats]:
    """The partition with the smallest largest halo, then the fewest neighbours (RCB or a
    grid); ties go to the first candidate (RCB, then grids in sorted order): deterministic."""
    best = None
    for name, owner in candidate_partitions(x, n_parts):
        st = partition_stats(owner, row_ptr, nbr, n_parts, name)
        key = (int(st.halo.max()), int(st.neighbours.max()))
        if best is None or key < best[0]:
            best = (key, owner, st)
    return best[1], best[2]
