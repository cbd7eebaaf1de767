"""``pdfem validate [--quick] [--report DIR] [--json] [--case NAME ...]``: check pdfem against
analytic references (:mod:`pdfem.validation`)."""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

from pdfem.cli.options import path_text
from pdfem.errors import EXIT_FAILURE, EXIT_OK, InputError

NAME = "validate"
HELP = "run the validation cases against analytic references (exit 0: all pass, 1: any fails)"

DESCRIPTION = """Run the validation cases of models/validation/ (wave speed, E and nu of the
LPS, cantilever frequency, momentum and energy in a coupled impact, pair vs full-family loop,
bar against a rigid wall, panel reaction) and compare each measured quantity with its cited
reference. Prints a table (case, quantity, pdfem, reference, error, tolerance, pass).
Exit status: 0 when every case passes, 1 when any fails, 2 for bad options."""


def add_arguments(v: argparse.ArgumentParser) -> None:
    """The options of ``pdfem validate``."""
    v.description = DESCRIPTION
    v.add_argument("--quick", action="store_true",
                   help="the smaller, shorter variant of every case (about a minute)")
    v.add_argument("--report", metavar="DIR", type=path_text,
                   help="write DIR/validation.md with a PNG plot per case (runs go to DIR/runs)")
    v.add_argument("--json", action="store_true",
                   help="print one JSON object with the same figures, nothing else on stdout")
    v.add_argument("--case", metavar="NAME", action="append", default=None,
                   help="run only this case (repeatable; default: all)")


def _report_dir(report: str) -> Path:
    """``--report`` checked like a run's ``--out`` (created; not a file; writable)."""
    from pdfem.run.outdir import check_out_dir
    try:
        return check_out_dir(report)
    except InputError as exc:
        raise InputError(None, "--report", exc.message, exc.value) from None


def run(args: argparse.Namespace) -> int:
    """Run the validation; exit status 0 when all cases pass, 1 otherwise."""
    from pdfem.validation import all_cases, run_validation
    from pdfem.validation.report import as_json, format_table, write_markdown

    cases = all_cases()
    if args.case:
        known = [c.name for c in cases]
        unknown = [n for n in args.case if n not in known]
        if unknown:
            raise InputError(None, "--case", "unknown validation case; the cases are: "
                             + ", ".join(known), unknown[0])
        cases = tuple(c for c in cases if c.name in args.case)

    def say(line: str) -> None:
        print(line, file=sys.stderr, flush=True)

    t0 = time.perf_counter()
    if args.report is not None:
        report = _report_dir(args.report)
        results = run_validation(cases, report / "runs", quick=args.quick, plot_dir=report, log=say)
    else:
        with tempfile.TemporaryDirectory(prefix="pdfem_validate_") as work:
            results = run_validation(cases, work, quick=args.quick, log=say)
    seconds = time.perf_counter() - t0
    if args.report is not None:
        say(f"validate: wrote {write_markdown(results, report, args.quick, seconds)}")
    if args.json:
        print(json.dumps(as_json(results, args.quick, seconds)))
    else:
        print(format_table(results, args.quick))
    return EXIT_OK if all(r.passed for r in results) else EXIT_FAILURE
