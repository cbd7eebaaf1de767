"""Load balance of an ice body split over MPI ranks: measure the imbalance, re-partition.

A rank's work is the bond count of its owned particles (intact or broken: the pair loop visits
both; a bond between two ranks counts on both). :func:`imbalance` is the largest rank's work
over the mean (1 = perfect; 1 for a whole body). :func:`rebalance` re-partitions a split body by
weighted recursive coordinate bisection of the current positions
(:func:`pdfem.parallel.rcb.rcb_owners`: no gather, the same result whatever the current
partition), moves the particles and bonds (:func:`pdfem.pd.layout.migration.migrate`) and
builds the rank's new part: a new halo plan and :class:`~pdfem.pd.layout.halo.HaloLayout` (its
``version`` one higher), and a new :class:`~pdfem.pd.body.IceBody` of the moved arrays (the
weighted volume of the intact bonds summed again from the broken bonds: the same bits; the
constraints' particle lists migrated as per-particle membership), which the old body object
then becomes. A whole body never moves.

Anything outside the body that keeps rank-local particle indices must be rebuilt after a
migration: it can tell by the body's ``layout_version`` (``docs/parallel.md``, "Load balance",
lists who holds such indices). Units: SI.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from pdfem.parallel.rcb import rcb_owners
from pdfem.pd.layout.halo import HaloLayout
from pdfem.pd.layout.migration import bond_work, halo_lists, migrate

def work(body) -> int:
    """This rank's work: the bond count of its owned particles."""
    b = body.bonds
    return int(bond_work(b.row_ptr, b.nbr, body.n)[body.layout.owned].sum())


def imbalance(body) -> float:
    """The largest rank's work over the mean work (-, 1 = balanced; collective)."""
    works = np.array(body.layout.comm.allgather(work(body)), dtype=np.float64)
    mean = works.mean()
    return float(works.max() / mean) if mean > 0 else 1.0


def rebalance(body, carry: dict[str, np.ndarray] | None = None):
    """Re-partition ``body`` over the ranks of its layout and move its particles and bonds
    (collective). Returns None when there is nothing to move (one process holds the body),
    else ``(new_body, carried)``: the rank's new part and the ``carry`` arrays (other
    per-particle arrays, (n_local, k) float64, e.g. a particle force's state) in its order."""
    lay = body.layout
    comm = lay.comm
    if comm.size == 1:
        return None
    t0 = time.perf_counter()
    b, own = body.bonds, lay.owned
    weight = bond_work(b.row_ptr, b.nbr, body.n)
    new = np.full(body.n, -1.0)
    new[own] = rcb_owners(body.y[own], lay.gid[own], weight[own], comm.size, comm, lay.n_global)
    lay.exchange(new)  # the halo's new owners, from their owners
    parts, owned, owner, carried = migrate(body, own, new.astype(np.int64), comm, carry)
    send, recv = halo_lists(parts["bonds"].row_ptr, parts["bonds"].nbr, owned, owner)
    plan = dataclasses.replace(lay.plan, local=parts.pop("gid"), owned=owned, pairs=None,
                               send=send, recv=recv)
    layout = HaloLayout(comm, plan, lay.n_global, lay.version + 1, lay.partition)
    layout.exchange_seconds = lay.exchange_seconds
    layout.rebalances = lay.rebalances + 1
    moved = type(body)(body.name, parts.pop("x0"), parts.pop("vol"), body.material, body.dx,
                       body.delta, parts.pop("bonds"), parts.pop("m"), layout=layout,
                       loop=body.loop, failure=body.failure,
                       influence_gain=body.influence_gain, **parts,
                       keep_bond_length=body.workspace.keep_bond_length)
    moved.local_external_work = body.local_external_work
    moved.local_fracture_dissipated = body.local_fracture_dissipated
    layout.rebalance_seconds = lay.rebalance_seconds + time.perf_counter() - t0
    return moved, carried
