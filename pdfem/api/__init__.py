"""pdfem's Python interface: load a case, change values, run it, read the results as arrays,
run parameter studies (docs/api.md).

::

    import pdfem
    case = pdfem.load_case("models/cylinder_ice_plate.toml",
                           overrides={"structure.0.motion.velocity": [0.0, -4.0, 0.0]})
    res = pdfem.run(case, out="results/cylinder_4ms")
    res.loads["cylinder"]["force"]                       # (steps, 3) N
    res.summary["loads"]["cylinder"]["magnitude"]["peak"]  # N, as pdfem post --json

- :func:`load_case` reads and validates a case file, with ``overrides`` (dotted paths into the
  TOML document, :mod:`pdfem.case.overrides`) applied before validation: a bad file, key or
  value raises :class:`~pdfem.errors.InputError` with the message ``pdfem run`` prints.
- :func:`run` runs a case in this process, as ``pdfem run`` does (the same function,
  :func:`pdfem.run.driver.run_case`; quiet unless asked), and returns its :class:`Results`;
  ``pdfem.run`` is this function (:mod:`pdfem`). A run that blows up raises
  :class:`~pdfem.errors.InstabilityError`, its results so far kept in ``out``.
- :func:`open_results` gives the :class:`Results` of an existing run
  (:mod:`pdfem.api.results`).
- :func:`sweep` and :func:`collect` are ``pdfem sweep`` (:mod:`pdfem.study`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping, Sequence

from pdfem.api.results import History, Results, open_results, unit_of
from pdfem.case import loader
from pdfem.case.config import Case
from pdfem.case.overrides import override_case
from pdfem.errors import InputError, InstabilityError

if TYPE_CHECKING:
    from pdfem.study import SweepTable

__all__ = ["Case", "History", "InputError", "InstabilityError", "Results", "collect",
           "load_case", "open_results", "run", "sweep", "unit_of"]


def load_case(path: str | os.PathLike, overrides: Mapping[str, Any] | None = None) -> Case:
    """Read and validate a case file, with values changed by ``overrides``.

    Parameters
    ----------
    path
        The case file (TOML, SI units).
    overrides
        ``{dotted path: value}``, e.g. ``{"ice.0.material.flexural_strength": 5e5,
        "run.end_time": 2e-3}``: list entries by their number from 0 (``ice.0`` is the first
        ``[[ice]]``), a value ``None`` removes a key (its default applies). Applied to the
        file's data before validation, so the schema's checks and messages apply.

    Returns
    -------
    Case
        The validated case (its ``text``: the changed case file, :mod:`pdfem.case.overrides`).

    Raises
    ------
    InputError
        A missing or invalid file, a path that cannot be followed (naming the key), or a value
        the schema refuses (naming the field): the message ``pdfem run`` would print.
    """
    case = loader.load_case(path)
    return override_case(case, overrides) if overrides else case


def run(case: Case | str | os.PathLike, out: str | os.PathLike | None = None, *,
        quiet: bool = True, restart: str | os.PathLike | None = None) -> Results:
    """Run a case in this process, as ``pdfem run`` does, and return its results.

    Parameters
    ----------
    case
        A case from :func:`load_case`, or a case file.
    out
        The output directory (default ``results/<case file name>``, as ``pdfem run``).
    quiet
        No messages or progress line (default); ``False`` prints what ``pdfem run`` prints.
    restart
        A checkpoint of this case to continue from (``out/checkpoint.h5``).

    Returns
    -------
    Results
        The run's results (``out/results.h5``); ``Results.run_summary`` holds the
        :class:`pdfem.run.driver.RunSummary` (steps, time step, wall time).

    Raises
    ------
    InputError
        A bad case or ``out`` (nothing is run).
    InstabilityError
        The run blew up (its results so far are in ``out``).
    """
    from pdfem.parallel.comm import run_guarded, world
    from pdfem.run.driver import run_case
    from pdfem.run.parallel import warm_before_ranks
    case = case if isinstance(case, Case) else loader.load_case(case)
    out = Path(out) if out is not None else Path("results") / Path(case.file).stem
    comm = world()  # under mpiexec every rank runs; rank 0 writes
    run_guarded(warm_before_ranks, comm, comm=comm)
    summary = run_guarded(run_case, case, out, quiet=quiet, restart=restart, comm=comm)
    comm.bcast(None)  # every rank reads the file once rank 0 has closed it
    results = open_results(summary.results)
    results.run_summary = summary
    return results


def sweep(case: Case | str | os.PathLike, grid: Mapping[str, Sequence[Any]],
          out: str | os.PathLike, *, jobs: int | None = None, threads: int | None = None,
          slurm: bool = False, plot: str | None = None,
          quiet: bool = False) -> SweepTable | Path | None:
    """A parameter study: ``pdfem sweep`` (docs/api.md; :func:`pdfem.study.sweep`).

    Parameters
    ----------
    case
        The base case: a case file, or a case from :func:`load_case`.
    grid
        ``{dotted key: values}``; the runs are the cartesian product of the values, e.g.
        ``{"ice.0.material.flexural_strength": [4e5, 6e5], "run.end_time": [1e-3]}``.
    out
        The study folder: ``runs/<name>/`` per run, ``summary.csv``, the plot.
    jobs
        Runs at once on this machine (default 1; with ``slurm``: the array's limit).
    threads
        Threads per run (default: cores / jobs; with ``slurm``: 1 core per task).
    slurm
        Write the SLURM job-array script ``out/sweep.sbatch`` and run nothing.
    plot
        ``OUTPUT:INPUT`` of the plot (default: the peak load against the first input).
    quiet
        No progress lines.

    Returns
    -------
    SweepTable or Path or None
        The table (``columns``, ``rows``: one dict per run, ``path`` of ``summary.csv``,
        ``plot``); with ``slurm``, the script's path (``None`` if every run is finished).

    Raises
    ------
    InputError
        A bad case, key or value (every run is validated before any runs).
    """
    from pdfem.study import sweep as study
    return study(case, grid, out, jobs=jobs, threads=threads, slurm=slurm, plot=plot,
                 say=(lambda s: None) if quiet else print)


def collect(out: str | os.PathLike, plot: str | None = None, *,
            quiet: bool = True) -> SweepTable:
    """``pdfem sweep --collect``: the table of a study (and its plot), written to
    ``out/summary.csv`` (:func:`pdfem.study.collect_study`).

    Parameters
    ----------
    out
        The study folder.
    plot
        ``OUTPUT:INPUT`` of the plot (default: the peak load against the first input).
    quiet
        No lines saying what was written (default).

    Returns
    -------
    SweepTable
        ``columns``, ``rows`` (one dict per run), ``inputs`` (the keys that vary), ``path``,
        ``plot``.
    """
    from pdfem.study import collect_study
    return collect_study(out, plot, say=(lambda s: None) if quiet else print)
