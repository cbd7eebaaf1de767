"""Load balance of an ice body split over MPI ranks: measure the imbalance, re-partition.

:class:`Rebalancing` is mixed into :class:`pdfem.pd.layout.halo.DistributedIce`. A rank's work
is the bond count of its owned particles (intact or broken: the pair loop visits both; a bond
between two ranks counts on both). :meth:`Rebalancing.imbalance` is the largest rank's work over
the mean (1 = perfect). :meth:`Rebalancing.rebalance` re-partitions the body by weighted
recursive coordinate bisection of the current positions (:func:`pdfem.parallel.rcb.rcb_owners`:
no gather, the same result whatever the current partition), moves the particles and bonds
(:func:`pdfem.pd.layout.migration.migrate`) and rebuilds what depends on the local numbering: the halo
plan, the pair workspace, the fracture ledger, the weighted volume of the intact bonds (summed
again from the broken bonds: the same bits), the counters of owned bonds, the constraints'
particle lists (migrated as per-particle membership).

Anything outside the body that keeps rank-local particle indices must be rebuilt after a
migration: it can tell by :attr:`Rebalancing.layout_version`, which every migration increments
(``docs/parallel.md``, "Load balance", lists who holds such indices). Units: SI.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from pdfem.parallel.rcb import rcb_owners
from pdfem.pd.bonds import kernels
from pdfem.pd.layout.migration import bond_work, halo_lists, migrate


class Rebalancing:
    """``work``, ``imbalance`` and ``rebalance`` of a split ice body (needs ``body``, ``plan``,
    ``comm``, ``global_n``, ``_exchange`` and ``_attach`` of the class it is mixed into)."""

    layout_version = 0
    """Incremented by every migration: the local particle numbering changed."""
    rebalances = 0
    """Migrations so far in this process."""
    rebalance_seconds = 0.0
    """Wall time (s) spent in re-partitions and migrations."""

    _work: tuple[int, int] = (-1, 0)  # (layout_version, work) of the last count

    def work(self) -> int:
        """This rank's work: the bond count of its owned particles (counted once per layout:
        bonds only break, they never move between particles)."""
        if self._work[0] != self.layout_version:
            b = self.body
            self._work = (self.layout_version,
                          int(bond_work(b.row_ptr, b.nbr, b.n)[self.plan.owned].sum()))
        return self._work[1]

    def imbalance(self) -> float:
        """The largest rank's work over the mean work (-, 1 = balanced; collective)."""
        works = np.array(self.comm.allgather(self.work()), dtype=np.float64)
        mean = works.mean()
        return float(works.max() / mean) if mean > 0 else 1.0

    def rebalance(self, carry: dict[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
        """Re-partition by weighted coordinate bisection of the current positions and move the
        particles and bonds to their new owners (see the module docstring; collective).
        ``carry``: other per-particle arrays ((n_local, k), e.g. a particle force's state) that
        move with the particles; returned in the new local order."""
        t0 = time.perf_counter()
        b, comm, own = self.body, self.comm, self.plan.owned
        weight = bond_work(b.row_ptr, b.nbr, b.n)
        new = np.full(b.n, -1.0)
        new[own] = rcb_owners(b.y[own], b.gid[own], weight[own], comm.size, comm, self.global_n)
        self._exchange(new)  # the halo's new owners, from their owners
        local, owned, owner, carried = migrate(b, own, new.astype(np.int64), comm, carry)
        send, recv = halo_lists(local.row_ptr, local.nbr, owned, owner)
        self.plan = dataclasses.replace(self.plan, local=local.gid, owned=owned, pairs=None,
                                        send=send, recv=recv)
        local._ws = kernels.PairWorkspace(local.row_ptr, local.nbr)
        spent = self.exchange_seconds
        self._attach(local)
        self.exchange_seconds = spent
        self.layout_version += 1
        self.rebalances += 1
        self.rebalance_seconds += time.perf_counter() - t0
        return carried
