"""``pdfem sweep CASE --set KEY=V1,V2,... [--set ...] [--out DIR] [--jobs N] [--threads T]
[--slurm] [--plot OUTPUT:INPUT]``: a parameter study; ``pdfem sweep --collect DIR``: its table.

The runs are the cartesian product of the ``--set`` values (:mod:`pdfem.study`), every case
validated before anything runs (a bad key or value: exit 2 naming it). Each runs as ``pdfem
run`` in ``DIR/runs/<name>/`` (``N`` at once, ``T`` threads each), finished runs skipped;
then ``DIR/summary.csv`` and a plot are written. ``--slurm`` writes the job-array script
``DIR/sweep.sbatch`` instead and runs nothing (docs/cluster.md). Exit status: 0 if every run
exited 0, 3 if the runs that did not blew up, 1 otherwise.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pdfem.errors import EXIT_OK, InputError

NAME = "sweep"
HELP = "a parameter study: run a case over a grid of values, collect a table"


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of ``pdfem sweep``."""
    p.add_argument("case", nargs="?", default=None, help="the base case file (TOML, SI units)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=V1,V2,...",
                   help="a dotted key of the case file and its values, e.g. "
                        "ice.0.material.flexural_strength=4e5,6e5 (list entries numbered from "
                        "0); repeat for more keys: the runs are every combination")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="the study folder (default: results/<case name>_sweep)")
    p.add_argument("--jobs", type=int, default=None, metavar="N",
                   help="runs at once on this machine (default 1); with --slurm, the job "
                        "array's limit of tasks at once (default: none)")
    p.add_argument("--threads", type=int, default=None, metavar="T",
                   help="threads per run (default: cores / jobs; with --slurm, cores per "
                        "task, default 1)")
    p.add_argument("--slurm", action="store_true",
                   help="write the SLURM job-array script DIR/sweep.sbatch and run nothing")
    p.add_argument("--collect", default=None, metavar="DIR",
                   help="write DIR/summary.csv (and the plot) of the study in DIR; run nothing")
    p.add_argument("--plot", default=None, metavar="OUTPUT:INPUT",
                   help="plot this column of summary.csv against this input (default: the "
                        "peak ice load against the first input)")


def run(args: argparse.Namespace) -> int:
    """Run the study, write its script or collect its table; exit status."""
    from pdfem.study import collect_study, parse_set, sweep, sweep_status
    if args.collect is not None:
        if args.case is not None or args.set or args.slurm:
            raise InputError(None, "--collect", "collects a study already run; give only the "
                             "folder: pdfem sweep --collect DIR [--plot OUTPUT:INPUT]")
        collect_study(args.collect, args.plot)
        return EXIT_OK
    if args.case is None or not args.set:
        raise InputError(None, "--set", "give the base case and at least one --set: pdfem "
                         "sweep CASE --set KEY=V1,V2,... --out DIR")
    grid: dict = {}
    for option in args.set:
        key, values = parse_set(option)
        if key in grid:
            raise InputError(None, f"--set {key}", "given twice; give each key once with all "
                             "its values")
        grid[key] = values
    out = args.out or Path("results") / f"{Path(args.case).stem}_sweep"
    table = sweep(args.case, grid, out, jobs=args.jobs, threads=args.threads,
                  slurm=args.slurm, plot=args.plot)
    if args.slurm or table is None:
        return EXIT_OK
    status = sweep_status([r["exit_status"] for r in table.rows])
    if status != EXIT_OK:
        failed = [f"{r['run']} (exit {r['exit_status']})" for r in table.rows
                  if r["exit_status"] != EXIT_OK]
        print(f"pdfem sweep: {len(failed)} of {len(table.rows)} runs did not finish well: "
              + ", ".join(failed) + f"; see their log.txt in {Path(out) / 'runs'}",
              file=sys.stderr)
    return status
