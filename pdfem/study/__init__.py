"""Parameter studies: a grid of runs of one case over values of its keys.

``pdfem sweep CASE --set KEY=V1,V2,... [--set ...] --out DIR`` (:mod:`pdfem.cli.sweep`) and
``pdfem.sweep(...)`` (:mod:`pdfem.api`) run the cartesian product of the values
(:mod:`~pdfem.study.grid`), every case validated first (:mod:`~pdfem.study.plan`), several at
once on this machine (:mod:`~pdfem.study.local`) or as a SLURM job array
(:mod:`~pdfem.study.slurm`), each in its own folder of the study (:mod:`~pdfem.study.folder`);
a study run again skips its finished runs. ``--collect`` makes the table of the runs' inputs
and key outputs (:mod:`~pdfem.study.table`) and a plot (:mod:`~pdfem.study.plot`).
"""

from pdfem.study.table import SweepTable, collect
from pdfem.study.grid import parse_set
from pdfem.study.plot import write_plot
from pdfem.study.runner import collect_study, sweep, sweep_status

__all__ = ["SweepTable", "collect", "collect_study", "parse_set", "sweep", "sweep_status", "write_plot"]
