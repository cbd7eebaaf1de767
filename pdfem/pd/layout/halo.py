"""A rank's part of an ice body split over MPI ranks: its owned particles and their halo.

A rank holds the particles it owns (a partition of the body: boxes of the lattice from the
distributed set-up, :mod:`pdfem.pd.layout.setup`, or any owner array, :mod:`pdfem.pd.layout.split`)
and their bond partners owned elsewhere (the halo), in global order, and every bond with at
least one owned end, in the global bond order. Each owned particle therefore has its whole
family, in the serial order. Bonds only break, so the pattern is fixed until the body is
re-partitioned (:mod:`pdfem.pd.layout.rebalance`). Per step the body exchanges the halo's
positions (before the dilatation pass) and dilatations (before the force pass); a bond between
an owned and a halo particle is evaluated on both ranks from the same values, so both decide
alike whether it breaks. :class:`HaloLayout` is the :class:`~pdfem.pd.layout.base.Layout` of
such a part. Units: SI.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from pdfem.parallel.exact_sum import exact_sum, exact_weighted_sums
from pdfem.pd.layout.base import WholeLayout


@dataclasses.dataclass
class HaloPlan:
    """Which particles a rank holds and what it exchanges.

    Attributes
    ----------
    local
        (n_local,) global indices of the local particles, ascending.
    owned
        (n_local,) bool, owned by this rank.
    pairs
        (P_local,) global indices of the local bonds, ascending (None when the part was built
        without the global bond list).
    send, recv
        neighbour rank -> local indices whose values are sent / received, in global order.
    """

    local: np.ndarray
    owned: np.ndarray
    pairs: np.ndarray | None
    send: dict
    recv: dict


def halo_plan(owner: np.ndarray, row_ptr: np.ndarray, nbr: np.ndarray, rank: int) -> HaloPlan:
    """The :class:`HaloPlan` of ``rank`` for the partition ``owner`` of a (global) pair list."""
    n = len(owner)
    i_of = np.repeat(np.arange(n, dtype=np.int64), np.diff(row_ptr))
    oi, oj = owner[i_of], owner[nbr]
    keep = (oi == rank) | (oj == rank)
    pairs = np.flatnonzero(keep)
    mine = owner == rank
    halo_from_j = nbr[keep & (oi == rank) & (oj != rank)]
    halo_from_i = i_of[keep & (oj == rank) & (oi != rank)]
    halo = np.unique(np.concatenate([halo_from_j, halo_from_i]))
    local = np.union1d(np.flatnonzero(mine), halo)
    g2l = np.full(n, -1, dtype=np.int64)
    g2l[local] = np.arange(len(local))
    owned = mine[local]
    recv = {int(q): g2l[halo[owner[halo] == q]] for q in np.unique(owner[halo])}
    # what q needs from us: our particles bonded to q's particles
    send = {}
    cross = keep & (oi != oj)
    for q in recv:  # halo relations are symmetric: we send to exactly the ranks we receive from
        a = i_of[cross & (oi == rank) & (oj == q)]
        b = nbr[cross & (oj == rank) & (oi == q)]
        send[q] = g2l[np.unique(np.concatenate([a, b]))]
    return HaloPlan(local, owned, pairs, send, recv)


def halo_exchange(comm, plan: HaloPlan, values: np.ndarray) -> float:
    """Overwrite the halo entries of ``values`` with their owners' values; returns the seconds
    it took."""
    t0 = time.perf_counter()
    sends = {q: values[idx] for q, idx in plan.send.items()}
    recvs = {q: ((len(idx),) + values.shape[1:], values.dtype) for q, idx in plan.recv.items()}
    for q, got in comm.exchange(sends, recvs).items():
        values[plan.recv[q]] = got
    return time.perf_counter() - t0


class HaloLayout:
    """The :class:`~pdfem.pd.layout.base.Layout` of a rank's part of a split body.

    Parameters
    ----------
    comm
        The communicator (:func:`pdfem.parallel.comm.world`).
    plan
        The rank's :class:`HaloPlan`.
    n_global
        Particles of the whole body.
    version
        Layout version (0 at set-up, incremented by every re-partition).
    partition
        How the partition was made (for the start-up report).
    """

    def __init__(self, comm, plan: HaloPlan, n_global: int, version: int = 0,
                 partition: str = "") -> None:
        self.partition = partition
        self.comm = comm
        self.plan = plan
        self.n_global = int(n_global)
        self.version = int(version)
        self.owned = plan.owned
        self.gid = plan.local
        self.owned_index = np.flatnonzero(plan.owned)
        self.counted_rows = plan.owned.astype(np.uint8)
        self.exchange_seconds = 0.0  # wall time spent in halo exchanges, s
        self.rebalances = 0  # re-partitions that led to this layout
        self.rebalance_seconds = 0.0  # wall time they took, s

    def exchange(self, values: np.ndarray) -> None:
        """Overwrite the halo rows of ``values`` with their owners' values (point to point)."""
        self.exchange_seconds += halo_exchange(self.comm, self.plan, values)

    def owned_sum(self, values: np.ndarray):
        """Correctly rounded sum of ``values`` over the owned rows of every rank (collective)."""
        return exact_sum(values, self.comm, self.owned_index)

    def total(self, values: np.ndarray):
        """Correctly rounded sum of every row of ``values`` (rows of owned particles) over
        every rank (collective)."""
        return exact_sum(values, self.comm)

    def weighted_sums(self, w: np.ndarray, values: np.ndarray, segments: list) -> np.ndarray:
        """Per segment of rows, ``sum w`` and ``sum w values``, correctly rounded over the
        processes (:func:`pdfem.parallel.exact_sum.exact_weighted_sums`; collective)."""
        return exact_weighted_sums(w, values, segments, self.comm)

    def allsum(self, value):
        """``value`` summed over the ranks in rank order (collective)."""
        return self.comm.allreduce_sum(value)

    def gather(self, values: np.ndarray) -> np.ndarray | None:
        """The owned rows of ``values`` in global order on rank 0 (None on the others)."""
        own = self.owned
        parts = self.comm.gather((self.gid[own], np.ascontiguousarray(values[own])))
        if parts is None:
            return None
        out = np.empty((self.n_global,) + values.shape[1:], dtype=values.dtype)
        for idx, vals in parts:
            out[idx] = vals
        return out


def make_layout(comm, plan: HaloPlan, n_global: int, partition: str = ""):
    """The layout of a part from a set-up: a :class:`HaloLayout`, or on one process (the part
    is the whole body) a :class:`~pdfem.pd.layout.base.WholeLayout`."""
    if comm.size == 1:
        return WholeLayout(n_global)
    return HaloLayout(comm, plan, n_global, partition=partition)
