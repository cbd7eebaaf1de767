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


def script_says(text: str, ranks: int, tmp_path: Path, test_file: str) -> str:
    """Run the Python source ``text`` on ``ranks`` ranks, with the test's folder and the tests'
    folder as its arguments (``sys.argv[1:]``, for its imports), and return what it printed
    after "ok" (rank 0's report); the test fails if a rank fails or nothing says "ok"."""
    script = tmp_path / "ranks_script.py"
    script.write_text(text)
    here = Path(test_file).parent
    r = run_script(script, ranks, here, here.parent, timeout=300)
    assert "ok" in r.stdout, r.stdout
    return r.stdout.split("ok", 1)[1].strip()
