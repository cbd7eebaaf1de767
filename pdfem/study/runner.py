"""A parameter study from start to end: validate the grid, run it here or write its job array,
collect the table.

:func:`sweep` is ``pdfem sweep CASE --set ...`` and ``pdfem.sweep(...)``: the grid's cases are
validated and written (:mod:`pdfem.study.plan`), then either run on this machine
(:mod:`pdfem.study.local`) and collected into ``summary.csv`` and a plot
(:mod:`pdfem.study.table`, :mod:`pdfem.study.plot`), or, with ``slurm=True``, left to a SLURM
job array whose script is written (:mod:`pdfem.study.slurm`) and nothing is run.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

from pdfem.case.config import Case
from pdfem.case.loader import load_case
from pdfem.errors import EXIT_FAILURE, EXIT_INSTABILITY, EXIT_OK, InputError
from pdfem.study.table import SweepTable, collect
from pdfem.study.local import default_threads, run_local
from pdfem.study.plan import plan_sweep
from pdfem.study.plot import write_plot
from pdfem.study.slurm import write_script


def _positive(name: str, value: int | None) -> None:
    if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 1):
        raise InputError(None, name, "give a whole number >= 1", value)


def sweep_status(statuses: Sequence[int | None]) -> int:
    """The exit status of a study from its runs': 0 if every run exited 0, else 3 if the others
    blew up (exit 3), else 1."""
    bad = [s for s in statuses if s != EXIT_OK]
    if not bad:
        return EXIT_OK
    return EXIT_INSTABILITY if all(s == EXIT_INSTABILITY for s in bad) else EXIT_FAILURE


def sweep(case: Case | str | os.PathLike, grid: Mapping[str, Sequence[Any]], out: str | os.PathLike,
          *, jobs: int | None = None, threads: int | None = None, slurm: bool = False,
          plot: str | None = None, say: Callable[[str], None] = print) -> SweepTable | Path | None:
    """Run the grid of ``case`` over ``grid`` in ``out`` (module docstring).

    Parameters
    ----------
    case
        The base case: a case file or a validated case (:func:`pdfem.case.load_case`).
    grid
        ``{dotted key: values}``, e.g. ``{"ice.0.material.flexural_strength": [4e5, 6e5]}``;
        the runs are the cartesian product (:mod:`pdfem.study.grid`).
    out
        The study folder (:mod:`pdfem.study.folder`).
    jobs
        Runs at once on this machine (default 1); with ``slurm``, the array's limit of tasks
        at once (default: none).
    threads
        Threads per run (default: this machine's cores / jobs; with ``slurm``, 1 core per task).
    slurm
        Write the SLURM job-array script ``out/sweep.sbatch`` and run nothing.
    plot
        ``OUTPUT:INPUT`` of the plot (:mod:`pdfem.study.plot`; default: its default plot).
    say
        Where the progress lines go.

    Returns
    -------
    SweepTable or Path or None
        The collected table (``out/summary.csv``); with ``slurm``, the script's path (``None``
        if every run is finished).

    Raises
    ------
    InputError
        A bad case, key or value (every run of the grid is validated before any runs), or
        ``out`` unusable. Nothing has run then.
    """
    _positive("--jobs", jobs)
    _positive("--threads", threads)
    base = case if isinstance(case, Case) else load_case(case)
    folder, runs = plan_sweep(base, grid, out)
    names = [r.name for r in runs]
    if slurm:
        todo = [n for n in names if not folder.finished(n)]
        if not todo:
            say(f"pdfem sweep: all {len(names)} runs in {folder.root} are finished; nothing to "
                f"submit (pdfem sweep --collect {folder.root})")
            return None
        path = write_script(folder, todo, threads or 1, jobs)
        say(f"pdfem sweep: {len(todo)} of {len(names)} runs to do, one task each: sbatch {path}")
        return path
    jobs = jobs or 1
    threads = threads or default_threads(jobs)
    say(f"pdfem sweep: {len(names)} runs of {base.file} in {folder.root}, {jobs} at once with "
        f"{threads} thread{'s' * (threads != 1)} each")
    run_local(folder, names, jobs, threads, say)
    return collect_study(folder.root, plot, say)


def collect_study(out: str | os.PathLike, plot: str | None = None,
                  say: Callable[[str], None] = print) -> SweepTable:
    """``pdfem sweep --collect DIR``: write ``DIR/summary.csv`` (:func:`pdfem.study.table.collect`)
    and the plot ``plot`` (``OUTPUT:INPUT``, :mod:`pdfem.study.plot`; by default its default
    plot, left out when the study has nothing to plot).

    Raises
    ------
    InputError
        ``out`` holds no study, or ``plot`` names no column of its table.
    """
    table = collect(out)
    say(f"pdfem sweep: table {table.path} ({len(table.rows)} runs)")
    try:
        table = dataclasses.replace(table, plot=write_plot(table, plot))
        say(f"pdfem sweep: plot {table.plot}")
    except InputError:
        if plot is not None:  # asked for; the default plot is left out when there is none
            raise
    return table
