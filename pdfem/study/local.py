"""Running a study's runs on this machine, several at once.

Each run is its own process, ``pdfem run runs/<name>/case.toml --out runs/<name>`` (the same
command a user types; its output appended to ``runs/<name>/log.txt``), with ``--restart`` from
its ``checkpoint.h5`` when an earlier try left one. At most ``jobs`` run at a time, each with
``threads`` threads (``NUMBA_NUM_THREADS`` and ``OMP_NUM_THREADS``; by default the cores this
process may use divided by ``jobs``, so that jobs x threads <= cores). A run's exit status goes
to its ``status.json`` when it ends (:mod:`pdfem.study.folder`); finished runs are skipped.

Stopping the study (Ctrl-C) stops the runs under way; they write no status, so the next sweep
runs them again (from their checkpoints, if they wrote any).
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

from pdfem.parallel.threads import node_cores, threads_per_rank
from pdfem.run.checkpoint import CHECKPOINT_NAME
from pdfem.study.folder import SweepFolder

POLL_SECONDS = 0.05
"""How often the runner looks whether a run has ended."""


def default_threads(jobs: int) -> int:
    """Threads per run when ``jobs`` run at once: this process's cores / jobs, at least 1."""
    return threads_per_rank(node_cores(), jobs)


def run_command(folder: SweepFolder, name: str) -> list[str]:
    """The command that runs (or continues) run ``name`` of ``folder``: ``pdfem run`` of this
    Python, with ``--restart`` if the run left a checkpoint."""
    out = folder.run_dir(name)
    cmd = [sys.executable, "-m", "pdfem.cli.main", "run", str(folder.case_file(name)),
           "--out", str(out)]
    if (out / CHECKPOINT_NAME).is_file():
        cmd += ["--restart", str(out / CHECKPOINT_NAME)]
    return cmd


@dataclass
class _Running:
    name: str
    process: subprocess.Popen
    start: float


def run_local(folder: SweepFolder, names: Sequence[str], jobs: int = 1, threads: int | None = None,
              say: Callable[[str], None] = print) -> dict[str, int]:
    """Run the unfinished runs among ``names``, ``jobs`` at a time.

    Parameters
    ----------
    folder
        The study folder, its case files written (:func:`pdfem.study.plan.plan_sweep`).
    names
        The runs to do, in order; finished ones are skipped.
    jobs
        Runs at once (>= 1).
    threads
        Threads per run (default :func:`default_threads`).
    say
        Where the progress lines go (one as each run starts and ends).

    Returns
    -------
    dict
        ``{name: exit status}`` of the runs that ran.
    """
    threads = threads or default_threads(jobs)
    env = {**os.environ, "NUMBA_NUM_THREADS": str(threads), "OMP_NUM_THREADS": str(threads)}
    todo = deque(n for n in names if not folder.finished(n))
    skipped = len(names) - len(todo)
    if skipped:
        say(f"pdfem sweep: {skipped} of {len(names)} runs finished before: skipped")
    total, done, statuses = len(todo), 0, {}
    running: list[_Running] = []
    try:
        while todo or running:
            while todo and len(running) < jobs:
                name = todo.popleft()
                folder.clear_status(name)
                cmd = run_command(folder, name)
                with open(folder.run_dir(name) / "log.txt", "a") as log:
                    log.write(f"$ pdfem {' '.join(cmd[3:])}\n")
                    log.flush()
                    process = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT,
                                               stdin=subprocess.DEVNULL, env=env)
                running.append(_Running(name, process, time.perf_counter()))
                say(f"  start {name}" + (" (from its checkpoint)" if "--restart" in cmd else "")
                    + f", {threads} thread{'s' * (threads != 1)}")
            time.sleep(POLL_SECONDS)
            for r in [r for r in running if r.process.poll() is not None]:
                running.remove(r)
                seconds = time.perf_counter() - r.start
                statuses[r.name] = status = r.process.returncode
                folder.write_status(r.name, status, seconds)
                done += 1
                say(f"  [{done}/{total}] {r.name}: exit {status} in {seconds:.1f} s"
                    + ("" if status == 0 else f" (see {Path(folder.run_dir(r.name)) / 'log.txt'})"))
    finally:  # stopped (Ctrl-C, an error): the runs under way end without a status
        for r in running:
            r.process.terminate()
        for r in running:
            r.process.wait()
    return statuses
