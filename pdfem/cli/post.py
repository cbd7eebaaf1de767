"""``pdfem post RESULTS.h5 [--plots DIR] [--csv FILE] [--lowpass HZ] [--json] [--sn CURVE ...]``:
summary table, plots, CSV; pressure-area envelope, patch loads and filtered peaks included;
with ``--sn`` the rainflow counts and Miner damage at the monitors (:mod:`pdfem.post.fatigue`)."""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import TYPE_CHECKING

from pdfem.cli.options import path_text
from pdfem.errors import EXIT_OK, InputError

if TYPE_CHECKING:
    from pdfem.post.fatigue import SNCurve

NAME = "post"
HELP = "summarise a results file: table, plots, CSV"


def add_arguments(q: argparse.ArgumentParser) -> None:
    """The options of ``pdfem post``."""
    q.add_argument("results", help="results file (results.h5 written by 'pdfem run')")
    q.add_argument("--plots", default=None, type=path_text, metavar="DIR",
                   help="write PNG plots into DIR")
    q.add_argument("--csv", default=None, type=path_text, metavar="FILE",
                   help="write the per-step load and monitor histories to FILE (CSV)")
    q.add_argument("--lowpass", type=float, default=None, metavar="HZ",
                   help="also report the load peaks after a zero-phase 4th-order Butterworth "
                        "low-pass at HZ (Hz, below half the coupling-step rate)")
    q.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    g = q.add_argument_group("fatigue at the monitors (rainflow, ASTM E1049; Miner sum)")
    g.add_argument("--sn", default=None, metavar="CURVE",
                   help="S-N curve: m=SLOPE,stress=RANGE_PA,cycles=N[,m2=SLOPE2,knee=N_KNEE], "
                        "e.g. m=3,stress=90e6,cycles=2e6,m2=5,knee=1e7 (DNV-RP-C203 D, air)")
    g.add_argument("--sn-monitor", action="append", default=None, metavar="NAME",
                   help="count this monitor only (repeatable; default: all)")
    g.add_argument("--sn-stress", default=None, metavar="STRESS",
                   help="stress counted: principal (signed, largest magnitude; the default), "
                        "xx, yy, zz, yz, xz, xy or von_mises (unsigned)")
    g.add_argument("--events", type=float, default=1.0, metavar="N",
                   help="repetitions of the simulated history (e.g. per year) the damage "
                        "is scaled to (default 1)")
    g.add_argument("--sn-bins", type=int, default=10, metavar="K",
                   help="range bins of the rainflow histogram (default 10)")


def _fatigue(args: argparse.Namespace, results: dict) -> tuple[dict, dict, SNCurve] | None:
    """The fatigue block, the cycles and the curve of ``--sn``; None without ``--sn``."""
    from pdfem.post.fatigue import fatigue_summary, monitor_cycles, parse_sn
    f = args.results
    if args.sn is None:
        extra = [o for o, v in (("--sn-monitor", args.sn_monitor), ("--sn-stress", args.sn_stress),
                                ("--events", args.events != 1.0), ("--sn-bins", args.sn_bins != 10))
                 if v]
        if extra:
            raise InputError(f, extra[0], "needs an S-N curve, --sn m=SLOPE,stress=RANGE_PA,"
                             "cycles=N (e.g. --sn m=3,stress=90e6,cycles=2e6)")
        return None
    if not (math.isfinite(args.events) and args.events > 0):
        raise InputError(f, "--events", "the repetitions of the simulated history must be a "
                         "finite number > 0", args.events)
    if args.sn_bins < 1:
        raise InputError(f, "--sn-bins", "the histogram needs at least 1 bin", args.sn_bins)
    curve = parse_sn(args.sn, f)
    stress, cycles = monitor_cycles(results, args.sn_stress, args.sn_monitor)
    return fatigue_summary(stress, cycles, curve, args.events, args.sn_bins), cycles, curve


def run(args: argparse.Namespace) -> int:
    """Summarise the results file; exit status."""
    from pdfem.post import format_summary, load_results, summarize, write_csv, write_plots
    results = load_results(args.results)
    fatigue = _fatigue(args, results)
    if args.lowpass is not None and not (math.isfinite(args.lowpass) and args.lowpass > 0):
        raise InputError(args.results, "--lowpass", "the cut-off must be a finite frequency > 0 Hz",
                         args.lowpass)
    try:
        summary = summarize(results, lowpass=args.lowpass)
    except ValueError as exc:  # the cut-off is above the Nyquist frequency
        raise InputError(args.results, "--lowpass", str(exc), args.lowpass) from None
    if fatigue:
        summary["fatigue"] = fatigue[0]
    written: list[str] = []
    if args.csv:
        try:
            write_csv(results, args.csv)
            if fatigue:
                from pdfem.post.fatigue_table import write_fatigue_csv
                summary["fatigue_csv"] = str(Path(args.csv).with_suffix("")) + "_rainflow.csv"
                write_fatigue_csv(fatigue[0], summary["fatigue_csv"])
        except OSError as exc:
            raise InputError(args.csv, "--csv", f"cannot write the CSV file ({exc})") from None
        summary["csv"] = args.csv
    if args.plots:
        try:
            written = [str(p) for p in write_plots(results, args.plots, args.lowpass)]
            if fatigue:
                from pdfem.post.fatigue_plot import write_fatigue_plots
                written += [str(p) for p in write_fatigue_plots(
                    fatigue[1], fatigue[2], fatigue[0]["stress"], args.plots, args.sn_bins)]
        except OSError as exc:
            raise InputError(args.plots, "--plots", f"cannot write the plots ({exc})") from None
        summary["plots"] = written
    if args.json:
        print(json.dumps(summary))
    else:
        print(format_summary(summary))
        if fatigue:
            from pdfem.post.fatigue_table import format_fatigue
            print("\n" + format_fatigue(fatigue[0]))
        if args.csv:
            print(f"\nCSV of the per-step histories: {args.csv}")
            if fatigue:
                print(f"CSV of the rainflow histograms: {summary['fatigue_csv']}")
        if args.plots:
            print(f"\nPlots in {args.plots}: " + (", ".join(Path(p).name for p in written)
                                                  or "none (nothing to plot)"))
    return EXIT_OK


