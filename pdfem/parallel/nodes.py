"""Which node (machine) each MPI rank runs on, and one figure per node (its free memory).

Ranks that share memory are found with MPI's shared-memory split
(``COMM_WORLD.Split_type(MPI.COMM_TYPE_SHARED)``): each group is one node, numbered in the order
of its first world rank. A per-node quantity (e.g. the memory available, in bytes) is measured
once per node by its first rank and shared with every rank. A serial run is one rank on node 0.
For a layout that does not exist yet (sizing a cluster job) :func:`block_layout` places ranks as
SLURM's block distribution does: ``ceil(ranks / nodes)`` consecutive ranks per node.
"""

from __future__ import annotations

import math
from typing import Callable


def node_layout(comm) -> list[int]:
    """The node index of every rank of ``comm`` (a :mod:`pdfem.parallel.comm` communicator),
    in rank order, the same list on every rank (collective under MPI)."""
    if comm.size == 1:
        return [0]
    from mpi4py import MPI

    shared = comm.comm.Split_type(MPI.COMM_TYPE_SHARED)
    first = shared.bcast(comm.rank, root=0)  # world rank of this node's first rank
    shared.Free()
    firsts = comm.allgather(first)
    order = sorted(set(firsts))
    return [order.index(f) for f in firsts]


def per_node(comm, nodes: list[int], measure: Callable[[], object]) -> list:
    """``measure()`` taken by the first rank of every node, one value per node (node order),
    the same list on every rank (collective under MPI).

    Parameters
    ----------
    comm
        The communicator of :func:`node_layout`.
    nodes
        Its node index per rank (:func:`node_layout`).
    measure
        What to measure on each node (e.g. the available memory in bytes).
    """
    first = nodes.index(nodes[comm.rank]) == comm.rank
    values = comm.allgather(measure() if first else None)
    return [values[nodes.index(k)] for k in range(max(nodes) + 1)]


def block_layout(n_ranks: int, n_nodes: int) -> list[int]:
    """Node index of each of ``n_ranks`` ranks placed ``ceil(n_ranks / n_nodes)`` per node
    in rank order (SLURM's default block distribution); fewer nodes are used if that many
    suffice."""
    if n_ranks < 1 or n_nodes < 1:
        raise ValueError(f"ranks and nodes must be positive, got {n_ranks} and {n_nodes}")
    per = math.ceil(n_ranks / n_nodes)
    return [r // per for r in range(n_ranks)]
