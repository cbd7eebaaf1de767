"""``pdfem info [--json]``: versions, threads and the MPI library."""

from __future__ import annotations

import argparse
import json
import platform

from pdfem import __version__
from pdfem.errors import EXIT_OK

NAME = "info"
HELP = "versions, threads and MPI"


def add_arguments(i: argparse.ArgumentParser) -> None:
    """The options of ``pdfem info``."""
    i.add_argument("--json", action="store_true", help="print one JSON object")


def versions() -> dict:
    """Versions of pdfem, Python and its dependencies, numba threads, the MPI library."""
    import numba
    out = {"pdfem": __version__, "python": platform.python_version(), "platform": platform.platform(),
           "numba_threads": numba.get_num_threads()}
    for mod in ("numpy", "scipy", "numba", "h5py", "meshio", "skfem", "gmsh", "matplotlib", "mpi4py"):
        try:
            m = __import__(mod)
            out[mod] = getattr(m, "__version__", "installed")
        except Exception as exc:  # an optional part that does not import is reported, not fatal
            out[mod] = f"unavailable ({type(exc).__name__}: {exc})"
    try:
        from mpi4py import MPI
        out["mpi_library"] = MPI.Get_library_version().splitlines()[0].strip()
    except Exception as exc:
        out["mpi_library"] = f"unavailable ({type(exc).__name__})"
    return out


def run(args: argparse.Namespace) -> int:
    """Print the versions; exit status."""
    info = versions()
    if args.json:
        print(json.dumps(info))
    else:
        for k, v in info.items():
            print(f"{k:>14}: {v}")
    return EXIT_OK


