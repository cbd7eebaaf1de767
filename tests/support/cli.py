"""Running the ``pdfem`` console script from a test, as a user would from a shell.

The tools are looked up next to the running interpreter first (the virtual environment the suite
runs in, where ``pip install`` put ``pdfem`` and the mpich wheel put ``mpiexec``), then on
``PATH``.
"""

from __future__ import annotations

import contextlib
import io
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Mapping


def tool(name: str) -> str:
    """Path of the executable ``name`` (``pdfem``, ``mpiexec``, ``lint-imports``).

    Raises
    ------
    FileNotFoundError
        Neither next to ``sys.executable`` nor on ``PATH``.
    """
    here = Path(sys.executable).parent / name
    if here.exists():
        return str(here)
    found = shutil.which(name)
    if found is None:
        raise FileNotFoundError(f"{name} is neither next to {sys.executable} nor on PATH: "
                                "install the package with its test extra")
    return found


def pdfem_command(ranks: int = 1) -> list[str]:
    """The command line that starts ``pdfem`` on ``ranks`` MPI ranks (no ``mpiexec`` for 1)."""
    if ranks == 1:
        return [tool("pdfem")]
    return [tool("mpiexec"), "-n", str(ranks), tool("pdfem")]


def run_pdfem(*args: str | Path, ranks: int = 1, cwd: Path | None = None, timeout: float = 600,
              env: Mapping[str, str] | None = None) -> subprocess.CompletedProcess:
    """Run ``pdfem ARGS`` on ``ranks`` ranks and capture its output (text).

    The exit status is not checked: tests of bad input expect 2.
    """
    return subprocess.run([*pdfem_command(ranks), *map(str, args)], capture_output=True,
                          text=True, cwd=cwd, timeout=timeout, env=env)


def run_ok(*args: str | Path, ranks: int = 1, **kwargs) -> subprocess.CompletedProcess:
    """:func:`run_pdfem` that fails the test, showing the end of stderr, unless it exits 0."""
    r = run_pdfem(*args, ranks=ranks, **kwargs)
    assert r.returncode == 0, f"pdfem {' '.join(map(str, args))} exited {r.returncode}:\n" \
                              f"{r.stderr[-3000:]}"
    return r



def run_main(*args: str | Path) -> subprocess.CompletedProcess:
    """``pdfem ARGS`` in this process: :func:`pdfem.cli.main.main`, the console script's code
    without an interpreter start (about 1 s each), with its standard output and error captured
    as :func:`run_pdfem` gives them. For the serial commands whose many variants a test runs
    (the bad-input corpus); a test that checks the console script itself uses :func:`run_pdfem`.
    """
    from pdfem.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in args])
    return subprocess.CompletedProcess(list(args), code, out.getvalue(), err.getvalue())
