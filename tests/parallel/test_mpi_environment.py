"""The MPI stack that pdfem installs works: mpiexec from the mpich wheel runs mpi4py ranks.

Run as an ``mpiexec -n 2`` subprocess with a timeout, so a broken MPI cannot hang the suite.
Reference: the sum over ranks of (rank + 1) for 2 ranks is 3.
"""

from __future__ import annotations

import os
import sys


from pdfem.parallel.threads import LOCAL_SIZE_VARIABLES, node_cores, ranks_on_node, threads_per_rank

from support.mpi import run_ranks


def test_two_ranks_allreduce():
    code = ("from mpi4py import MPI; c = MPI.COMM_WORLD; "
            "s = c.allreduce(c.rank + 1); print(c.size, s) if c.rank == 0 else None")
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    r = run_ranks(2, sys.executable, "-c", code, timeout=120, env=env)
    assert r.stdout.split() == ["2", "3"]


def test_ranks_on_a_node_share_its_cores():
    """Two ranks on this node each run numba, BLAS and OpenMP on cores // 2 threads (at least
    1): the pools of K ranks together never exceed the node's cores."""
    # rank 0 prints both ranks' counts (two ranks printing to one pipe may interleave)
    code = ("from pdfem.parallel.comm import world; import numba; "
            "from threadpoolctl import threadpool_info; w = world(); "
            "mine = [numba.get_num_threads(), *sorted({p['num_threads'] for p in threadpool_info()})]; "
            "every = w.allgather(mine); print(every) if w.rank == 0 else None")
    r = run_ranks(2, sys.executable, "-c", code, timeout=120)
    expected = threads_per_rank(node_cores(), 2)
    assert r.stdout.strip() == str([[expected, expected]] * 2), r.stdout


def test_threads_per_rank_and_the_launchers_local_size(monkeypatch):
    """cores // ranks on the node, at least 1; the node's ranks from the launcher's variable,
    else the world's size."""
    assert threads_per_rank(8, 3) == 2 and threads_per_rank(2, 4) == 1 and threads_per_rank(2, 1) == 2
    for name in LOCAL_SIZE_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    assert ranks_on_node(6) == 6
    monkeypatch.setenv("OMPI_COMM_WORLD_LOCAL_SIZE", "3")
    assert ranks_on_node(6) == 3
