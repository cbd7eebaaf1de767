"""The MPI stack that pdfem installs works: mpiexec from the mpich wheel runs mpi4py ranks.

Run as an ``mpiexec -n 2`` subprocess with a timeout, so a broken MPI cannot hang the suite.
Reference: the sum over ranks of (rank + 1) for 2 ranks is 3.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest


def _mpiexec() -> str | None:
    here = Path(sys.executable).parent / "mpiexec"
    return str(here) if here.exists() else shutil.which("mpiexec")


def test_two_ranks_allreduce():
    mpiexec = _mpiexec()
    if mpiexec is None:
        pytest.fail("no mpiexec found: the mpich wheel should provide one next to the Python executable")
    code = ("from mpi4py import MPI; c = MPI.COMM_WORLD; "
            "s = c.allreduce(c.rank + 1); print(c.size, s) if c.rank == 0 else None")
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    r = subprocess.run([mpiexec, "-n", "2", sys.executable, "-c", code], capture_output=True,
                       text=True, timeout=120, env=env)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["2", "3"]
