"""Launching a Python script or a module on K MPI ranks from a test.

Every launch goes through ``mpiexec`` of the mpich wheel (:func:`support.cli.tool`) with a
timeout, so a broken MPI fails the test instead of hanging the suite.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Mapping

from support.cli import tool


def mpiexec(ranks: int, *args: str | Path) -> list[str]:
    """The command line ``mpiexec -n RANKS ARGS``."""
    return [tool("mpiexec"), "-n", str(ranks), *map(str, args)]


def run_ranks(ranks: int, *args: str | Path, timeout: float = 600,
              env: Mapping[str, str] | None = None, cwd: Path | None = None,
              check: bool = True) -> subprocess.CompletedProcess:
    """Run ``mpiexec -n RANKS ARGS`` and capture its output (text).

    With ``check`` (the default) the test fails, showing the end of stderr, unless every rank
    exits 0.
    """
    r = subprocess.run(mpiexec(ranks, *args), capture_output=True, text=True, timeout=timeout,
                       env=env, cwd=cwd)
    if check:
        assert r.returncode == 0, f"{ranks} ranks exited {r.returncode}:\n{r.stderr[-3000:]}"
    return r


def run_script(script: Path, ranks: int, *args: str | Path, **kwargs
               ) -> subprocess.CompletedProcess:
    """Run the Python file ``script`` with ``ARGS`` on ``ranks`` ranks (see :func:`run_ranks`)."""
    return run_ranks(ranks, sys.executable, script, *args, **kwargs)
