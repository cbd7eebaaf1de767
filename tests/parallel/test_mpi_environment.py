"""The MPI stack that pdfem installs works: mpiexec from the mpich wheel runs mpi4py ranks.

Run as an ``mpiexec -n 2`` subprocess with a timeout, so a broken MPI cannot hang the suite.
Reference: the sum over ranks of (rank + 1) for 2 ranks is 3.
"""

from __future__ import annotations

import os
import sys


from support.mpi import run_ranks


def test_two_ranks_allreduce():
    code = ("from mpi4py import MPI; c = MPI.COMM_WORLD; "
            "s = c.allreduce(c.rank + 1); print(c.size, s) if c.rank == 0 else None")
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    r = run_ranks(2, sys.executable, "-c", code, timeout=120, env=env)
    assert r.stdout.split() == ["2", "3"]
