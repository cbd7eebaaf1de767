"""Fixtures shared by the whole suite, and the workers' share of the cores.

The suite runs on pytest-xdist workers (``-n 2`` in ``pyproject.toml``); each worker takes its
share of the machine's cores for numba and BLAS, as an MPI rank does
(:mod:`pdfem.parallel.threads`), so that the workers do not spin threads on each other's
cores. Results do not depend on the thread count.

``gmsh_box`` writes a gmsh mesh of an axis-aligned box with named volume and face groups
(:func:`support.meshes.write_box`), which the FE, rigid-body and coupling tests mesh.
"""

from __future__ import annotations

from pathlib import Path
import os
from typing import Callable

import pytest

from pdfem.parallel.threads import limit_threads, node_cores, threads_per_rank

from support.meshes import write_box


@pytest.fixture(scope="session")
def gmsh_box() -> Callable[..., Path]:
    """:func:`write_box`: writes a gmsh mesh of a box with named volume and face groups."""
    return write_box


def pytest_configure(config) -> None:
    """On an xdist worker: numba and BLAS threads = cores // workers."""
    workers = os.environ.get("PYTEST_XDIST_WORKER_COUNT", "")
    if workers.isdigit():
        limit_threads(threads_per_rank(node_cores(), int(workers)))


FIRST = ("validation/test_validate.py", "pd/test_strength.py", "models/test_mpi_models.py",
         "validation/test_step_sweep.py", "validation/test_propeller.py",
         "forces/test_mpi_short_range.py", "run/test_mpi_run.py", "run/test_determinism.py",
         "coupling/test_bow_panel.py", "output/test_paraview.py", "validation/test_cantilever.py",
         "pd/test_verification.py", "pd/test_mpi_distributed.py", "run/test_checkpoint.py",
         "study/test_sweep.py", "run/test_stop.py",
         "pd/test_distributed_setup.py", "coupling/test_coupling.py",
         "validation/test_validation_plate.py", "pd/test_mpi_rebalance.py",
         "fem/test_fem_cantilever.py", "run/test_mpi_checkpoint_ranks.py",
         "validation/test_plate_convergence.py", "pd/test_crushed_shear.py",
         "forces/test_water.py", "validation/test_winkler.py", "motion/test_attached.py")
"""The suite's files of 10 s and more, longest first (0.5-3 min on one core for the first
seven; BENCHMARKS.md, "Test suite"). They are collected first, so that the workers start them
first (``--dist loadfile`` hands the files out in collection order: longest first is the
classic schedule for two machines) and finish together on the many short files."""


def pytest_collection_modifyitems(config, items) -> None:
    """The files of :data:`FIRST` first, in that order; the rest as collected."""
    rank = {name: k for k, name in enumerate(FIRST)}

    def key(item) -> int:
        path = item.nodeid.split("::", 1)[0].removeprefix("tests/")
        return rank.get(path, len(FIRST))

    items.sort(key=key)  # stable: the order within a file and among the rest is kept
