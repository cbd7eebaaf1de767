"""The MPI stack that pdfem installs works: mpiexec from the mpich wheel runs mpi4py ranks.

Run as an ``mpiexec -n 2`` subprocess with a timeout, so a broken MPI cannot hang the suite.
Reference: the sum over ranks of (rank + 1) for 2 ranks is 3.
"""

from __future__ import annotations

import os
import subprocess
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
    """Two ranks on this node each run numba and OpenMP on cores // 2 threads (at least 1):
    the pools of K ranks together never exceed the node's cores; BLAS on one (on this 2-core
    machine also cores // 2)."""
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


def test_a_serial_run_keeps_blas_on_one_thread():
    """A run's communicator (one process) leaves BLAS on one thread: its threads' start-up
    made a structure's 15,000-value dot product 350 times slower (pdfem.parallel.threads)."""
    code = ("from threadpoolctl import threadpool_info; from pdfem.parallel.comm import world; "
            "world(); print(sorted({p['num_threads'] for p in threadpool_info() "
            "if p['user_api'] == 'blas'}))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env={k: v for k, v in os.environ.items() if "MPI" not in k and "PMI" not in k})
    assert r.stdout.strip() == "[1]", r.stdout + r.stderr
