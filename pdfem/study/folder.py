"""The folder of a parameter study and what it records about each run.

::

    DIR/sweep.json                 the study: its base case, its keys, its runs in grid order
    DIR/runs/<name>/case.toml      the run's case file (the base case with the run's values)
    DIR/runs/<name>/results.h5     what ``pdfem run`` writes there (+ results.xdmf, checkpoints)
    DIR/runs/<name>/log.txt        the run's standard output and error
    DIR/runs/<name>/status.json    {"exit_status": N}, written when ``pdfem run`` has ended
    DIR/summary.csv, DIR/*.png     the table and plot of ``pdfem sweep --collect``
    DIR/sweep.sbatch               the job-array script of ``pdfem sweep --slurm``

A run is *finished* when its ``status.json`` holds exit status 0 (done) or 3 (stopped by a
blow-up, which a second try would repeat: runs are deterministic). Any other status, or none (a
run killed, a task that never started), leaves it to be run again, from its checkpoint when it
wrote one. Both the local runner (:mod:`pdfem.study.local`) and the SLURM script
(:mod:`pdfem.study.slurm`) write ``status.json`` this way, so either can take up a study the
other began.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pdfem.errors import EXIT_INSTABILITY, EXIT_OK, InputError

MANIFEST = "sweep.json"
"""The study's description in its folder."""

STATUS = "status.json"
"""A run's exit status, in its folder."""

FINISHED = (EXIT_OK, EXIT_INSTABILITY)
"""Exit statuses of a finished run (module docstring)."""


@dataclass(frozen=True)
class SweepFolder:
    """Paths and records of a study folder (module docstring)."""

    root: Path

    def run_dir(self, name: str) -> Path:
        """The folder of run ``name``: its ``--out``."""
        return self.root / "runs" / name

    def case_file(self, name: str) -> Path:
        """The case file of run ``name``."""
        return self.run_dir(name) / "case.toml"

    def results(self, name: str) -> Path:
        """The results file of run ``name``."""
        return self.run_dir(name) / "results.h5"

    def status(self, name: str) -> int | None:
        """The exit status run ``name`` recorded, ``None`` if it has not ended (or not run)."""
        try:
            return int(json.loads((self.run_dir(name) / STATUS).read_text())["exit_status"])
        except (OSError, ValueError, KeyError, TypeError):
            return None

    def finished(self, name: str) -> bool:
        """Whether run ``name`` is finished (module docstring)."""
        return self.status(name) in FINISHED

    def clear_status(self, name: str) -> None:
        """Forget the status of run ``name`` (before it runs again)."""
        (self.run_dir(name) / STATUS).unlink(missing_ok=True)

    def write_status(self, name: str, exit_status: int, wall_seconds: float) -> None:
        """Record how run ``name`` ended (written whole: a temporary file renamed)."""
        path = self.run_dir(name) / STATUS
        tmp = path.with_suffix(".json.tmp")
        tmp.write_text(json.dumps({"exit_status": exit_status,
                                   "wall_seconds": round(wall_seconds, 3)}) + "\n")
        os.replace(tmp, path)

    def read_manifest(self) -> dict[str, Any] | None:
        """``sweep.json`` (``case``, ``keys``, ``runs``: ``[{"name", "values"}]``), ``None``
        if the folder holds no study.

        Raises
        ------
        InputError
            If the file is there but not a study's description.
        """
        path = self.root / MANIFEST
        if not path.is_file():
            return None
        try:
            data = json.loads(path.read_text())
            if not (isinstance(data["keys"], list) and isinstance(data["runs"], list)):
                raise ValueError("keys and runs must be lists")
            return data
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise InputError(str(path), None, f"not the description of a pdfem sweep ({exc}); "
                             "give the folder a sweep wrote (pdfem sweep CASE --set ... --out "
                             "DIR)") from None

    def write_manifest(self, data: dict[str, Any]) -> None:
        """Write ``sweep.json`` (whole: a temporary file renamed)."""
        path = self.root / MANIFEST
        tmp = path.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(data, indent=1) + "\n")
        os.replace(tmp, path)
