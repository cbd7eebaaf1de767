"""Threads per rank: ranks that share a node share its cores.

A rank runs two thread pools: numba's (the bond, contact, water and structure kernels) and
the BLAS library's under numpy. Each pool starts as many threads as the node has cores, so K
ranks on one node would run K times too many threads; the waiting threads of one rank then
spin on the cores the others compute on. Measured on 2 cores, 2 ranks
(models/panel_pressure_pulse.toml shortened to 2 ms): 17.4 s with both pools at 2 threads per
rank, 5.0 s with BLAS at 1 (docs/parallel.md). So under MPI each rank takes
``max(1, cores // ranks on its node)`` threads in numba's pool.

BLAS runs on one thread always (:func:`single_thread_blas`, every run): what a run asks of it
are small products (a structure's work accounts, 3 x 3 rotations), which its threads' start-up
only slows down. Measured on 2 cores with the other core busy: ``(a + b) @ (c - d)`` on
14,967 values takes 5.3 ms with BLAS on 2 threads, 15 us on 1.

Results do not depend on the number of threads: the kernels' sums are taken in a fixed order
(docs/parallel.md, "Determinism").
"""

from __future__ import annotations

import os


def node_cores() -> int:
    """Cores this process may run on (its CPU affinity; ``os.cpu_count()`` where unknown)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def threads_per_rank(cores: int, ranks_on_node: int) -> int:
    """Threads of each rank when ``ranks_on_node`` ranks share ``cores`` cores (at least 1)."""
    return max(1, cores // max(1, ranks_on_node))


LOCAL_SIZE_VARIABLES = ("MPI_LOCALNRANKS", "OMPI_COMM_WORLD_LOCAL_SIZE", "PMIX_LOCAL_SIZE")
"""Variables in which MPI launchers (MPICH's hydra, Open MPI, PMIx) give the ranks on a node."""


def ranks_on_node(world_size: int) -> int:
    """Ranks sharing this node, from the launcher's environment; ``world_size`` where it is
    silent (as if every rank shared the node: never more threads than cores)."""
    for name in LOCAL_SIZE_VARIABLES:
        value = os.environ.get(name, "")
        if value.isdigit() and int(value) > 0:
            return int(value)
    return world_size


def share_node_cores(world_size: int) -> int:
    """Limit this rank's numba and BLAS threads to its share of the node's cores.

    No communication: every rank can call it at any time.

    Parameters
    ----------
    world_size
        Ranks of the run (used where the launcher does not say how many share the node).

    Returns
    -------
    int
        Threads per pool of this rank.
    """
    return limit_threads(threads_per_rank(node_cores(), ranks_on_node(world_size)))


def limit_threads(n: int) -> int:
    """Run numba's kernels and the loaded OpenMP libraries on at most ``n`` threads, BLAS on one.

    Returns
    -------
    int
        Threads of numba's pool now (``n``, or fewer where ``NUMBA_NUM_THREADS`` says so).
    """
    import numba
    from threadpoolctl import threadpool_limits

    n = min(max(1, n), numba.config.NUMBA_NUM_THREADS)
    numba.set_num_threads(n)
    threadpool_limits(limits=n)
    single_thread_blas()
    return n


def single_thread_blas() -> None:
    """Run the loaded BLAS library on one thread (module docstring)."""
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1, user_api="blas")
