"""``pdfem post RESULTS.h5 [--plots DIR] [--csv FILE] [--lowpass HZ] [--json]``: summary table,
plots, CSV; pressure-area envelope, patch loads and filtered peaks included."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from pdfem.errors import EXIT_OK, InputError

NAME = "post"
HELP = "summarise a results file: table, plots, CSV"


def add_arguments(q: argparse.ArgumentParser) -> None:
    """The options of ``pdfem post``."""
    q.add_argument("results", help="results file (results.h5 written by 'pdfem run')")
    q.add_argument("--plots", default=None, metavar="DIR", help="write PNG plots into DIR")
    q.add_argument("--csv", default=None, metavar="FILE",
                   help="write the per-step load and monitor histories to FILE (CSV)")
    q.add_argument("--lowpass", type=float, default=None, metavar="HZ",
                   help="also report the load peaks after a zero-phase 4th-order Butterworth "
                        "low-pass at HZ (Hz, below half the coupling-step rate)")
    q.add_argument("--json", action="store_true", help="print the summary as one JSON object")


def run(args: argparse.Namespace) -> int:
    """Summarise the results file; exit status."""
    from pdfem.post import format_summary, load_results, summarize, write_csv, write_plots
    results = load_results(args.results)
    if args.lowpass is not None and not args.lowpass > 0:
        raise InputError(args.results, "--lowpass", "the cut-off must be a frequency > 0 Hz",
                         args.lowpass)
    try:
        summary = summarize(results, lowpass=args.lowpass)
    except ValueError as exc:  # the cut-off is above the Nyquist frequency
        raise InputError(args.results, "--lowpass", str(exc), args.lowpass) from None
    written: list[str] = []
    if args.csv:
        try:
            write_csv(results, args.csv)
        except OSError as exc:
            raise InputError(args.csv, "--csv", f"cannot write the CSV file ({exc})") from None
        summary["csv"] = args.csv
    if args.plots:
        try:
            written = [str(p) for p in write_plots(results, args.plots, args.lowpass)]
        except OSError as exc:
            raise InputError(args.plots, "--plots", f"cannot write the plots ({exc})") from None
        summary["plots"] = written
    if args.json:
        print(json.dumps(summary))
    else:
        print(format_summary(summary))
        if args.csv:
            print(f"\nCSV of the per-step histories: {args.csv}")
        if args.plots:
            print(f"\nPlots in {args.plots}: " + (", ".join(Path(p).name for p in written)
                                                  or "none (nothing to plot)"))
    return EXIT_OK


