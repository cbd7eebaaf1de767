"""``pdfem run [CASE.toml] [--out DIR] [--restart CHECKPOINT] [--quiet] [--json]``: run a case.

``pdfem run CASE --estimate [--ranks N] [--nodes K] [--node-memory 24GB] [--setup S]`` sizes the
run without building it (:mod:`pdfem.run.sizing`): memory per rank and per node, time per step
and projected wall time; exit 0 if every node holds its ranks, 2 (saying how many nodes it
needs) if not. It writes nothing (``--out`` is not created).

``pdfem run CASE --profile`` also times the run's components (:mod:`pdfem.run.profile`).

``pdfem run CASE --restart DIR/checkpoint.h5`` continues a run of CASE from its last checkpoint,
appending to the results file in DIR (``--out`` defaults to the checkpoint's directory).

SIGTERM, SIGUSR1 or a first Ctrl-C (SIGINT) stop the run at the end of its coupling step with a
checkpoint and a last frame (:mod:`pdfem.run.stop`): exit status 4 and a message giving the
restart command; a second Ctrl-C stops at once (exit 1). A results or checkpoint file that
cannot be written (no space left, a file-size limit, an I/O error) ends the run with exit 1 and
one paragraph saying what was kept (:mod:`pdfem.output.room`).
Without a case it runs the built-in demo (``demo_ice_sheet_panel.toml`` of the package
``pdfem.models``) into ``results/demo_ice_sheet_panel/`` and prints its post summary.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.resources
import io
import json
import shlex
import sys
from pathlib import Path

from pdfem.cli.options import path_text
from pdfem.errors import EXIT_BAD_INPUT, EXIT_OK, EXIT_STOPPED, InputError

NAME = "run"
HELP = "run a case file (no case: the built-in demo)"
EPILOG = ("exit status: 0 done, 1 an error (a results or checkpoint file that cannot be written "
          "included), 2 bad input, 3 the run blew up, 4 stopped by SIGTERM, SIGUSR1 or Ctrl-C "
          "(SIGINT) at the end of a coupling step with a checkpoint: continue it with "
          "pdfem run CASE --out DIR --restart DIR/checkpoint.h5 (a second Ctrl-C stops at once)")

DEMO_CASE = "demo_ice_sheet_panel.toml"
"""The built-in demo case (package data of ``pdfem.models``) that ``pdfem run`` runs without a case."""


def add_arguments(r: argparse.ArgumentParser) -> None:
    """The options of ``pdfem run``."""
    r.epilog = EPILOG
    r.add_argument("case", nargs="?", default=None,
                   help=f"case file (TOML, SI units); default: the demo {DEMO_CASE}")
    r.add_argument("--out", default=None, type=path_text,
                   help="output directory (default: results/<case name>)")
    r.add_argument("--restart", default=None, type=path_text, metavar="CHECKPOINT",
                   help="continue the run of CASE from this checkpoint (checkpoint.h5 in the "
                        "run's output directory), appending to its results")
    r.add_argument("--quiet", action="store_true", help="no progress or messages")
    r.add_argument("--json", action="store_true", help="print the run summary as one JSON object")
    r.add_argument("--profile", action="store_true",
                   help="time the run's components (bonds, contact, water, structures, output, "
                        "the rest): a table after the summary, profile.json in --out")
    e = r.add_argument_group("sizing a run (docs/cluster.md)")
    e.add_argument("--estimate", action="store_true",
                   help="build nothing: print memory per rank and per node, time per step and "
                        "projected wall time, then exit (0 fits, 2 does not)")
    e.add_argument("--ranks", type=int, default=None,
                   help="with --estimate: ranks of the planned job (default: this MPI world)")
    e.add_argument("--nodes", type=int, default=None,
                   help="with --estimate: nodes of the planned job, ranks spread ceil(N/K) per "
                        "node (default 1 with --ranks; else this MPI world's nodes)")
    e.add_argument("--node-memory", default=None, metavar="BYTES",
                   help="with --estimate: memory of one node, e.g. 24GB, 24GiB, 2.5e10 "
                        "(default: MemAvailable of the node)")
    e.add_argument("--setup", choices=("distributed", "global"), default=None,
                   help="with --estimate: the set-up to size for (default: distributed, the one "
                        "runs use; global: every rank would first build the whole ice body)")


def demo_case_file() -> contextlib.AbstractContextManager[Path]:
    """The built-in demo case, a file of the package ``pdfem.models``, as a context manager
    giving its path on disk."""
    return importlib.resources.as_file(importlib.resources.files("pdfem.models") / DEMO_CASE)


def _budget(row: dict | None) -> list[dict] | None:
    """The energy budget of the last frame as ``[{"term", "joules", "percent_of_input"}, ...]``."""
    if not row:
        return None
    from pdfem.run.energy import budget
    return [{"term": label, "joules": value, "percent_of_input": pct}
            for label, value, pct in budget(row)]


def _estimate(args: argparse.Namespace, case) -> int:
    """``--estimate``: print the sizing of the run on rank 0; exit status 0 or 2."""
    from pdfem.parallel.comm import run_guarded, world
    from pdfem.run.sizing import estimate_report, parse_bytes
    for name, value in (("--ranks", args.ranks), ("--nodes", args.nodes)):
        if value is not None and value < 1:
            raise InputError(None, name, "give a positive whole number", value)
    memory = None if args.node_memory is None else parse_bytes(args.node_memory)
    setup = args.setup != "global"  # runs use the distributed set-up
    comm = world()
    from pdfem.run.parallel import warm_before_ranks
    run_guarded(warm_before_ranks, comm, comm=comm)
    lines, refusal = run_guarded(estimate_report, case, comm, args.ranks, args.nodes, memory,
                                 setup, comm=comm)
    if comm.rank == 0:
        print("\n".join(lines), flush=True)
        if refusal is not None:
            raise refusal
    return EXIT_OK if refusal is None else EXIT_BAD_INPUT


def run(args: argparse.Namespace) -> int:
    """Run the case (or the demo); exit status."""
    from pdfem.case.schema import load_case
    if args.estimate and args.case is None:
        raise InputError(None, "--estimate", "give the case file to size: "
                         "pdfem run CASE.toml --estimate [--ranks N] [--nodes K]")
    if not args.estimate and (args.ranks, args.nodes, args.node_memory, args.setup) != (
            None, None, None, None):
        raise InputError(None, "--ranks/--nodes/--node-memory/--setup", "these size a planned "
                         "job and go with --estimate: pdfem run CASE.toml --estimate --ranks N")
    if args.estimate:
        return _estimate(args, load_case(args.case))
    from pdfem.run.driver import run_case
    if args.case is None:  # the demo: run it, then summarise its results
        with demo_case_file() as path:
            if not path.is_file():
                raise InputError(str(path), None, "the built-in demo case is missing from this "
                                 "installation; give a case file: pdfem run CASE.toml")
            case = load_case(path)
        stem = Path(DEMO_CASE).stem
    else:
        case = load_case(args.case)
        stem = Path(args.case).stem
    if args.restart is not None and args.case is None:
        raise InputError(None, "--restart", "give the case file of the run to continue: "
                         "pdfem run CASE.toml --restart CHECKPOINT")
    if args.out:
        out = Path(args.out)
    elif args.restart is not None:
        out = Path(args.restart).parent
    else:
        out = Path("results") / stem
    demo = args.case is None
    from pdfem.parallel.comm import run_guarded, world
    from pdfem.run.stop import stop_signals
    comm = world()  # under mpiexec: every rank runs, rank 0 writes and reports
    from pdfem.run.parallel import warm_before_ranks
    with stop_signals() as stop:  # SIGTERM, SIGUSR1, SIGINT: stop with a checkpoint
        run_guarded(warm_before_ranks, comm, comm=comm)  # one rank fills numba's cache first
        if args.json:
            buf = io.StringIO()
            with contextlib.redirect_stdout(buf):
                summary = run_guarded(run_case, case, out, quiet=True, restart=args.restart,
                                      comm=comm, profile=args.profile, stop=stop)
        else:
            summary = run_guarded(run_case, case, out, quiet=args.quiet, restart=args.restart,
                                  comm=comm, profile=args.profile, stop=stop)
    if comm.rank != 0:
        return EXIT_STOPPED if summary.stopped else EXIT_OK
    restart = _restart_command(case.file, out, summary.checkpoint, comm.size)
    if args.json:
        report = {"results": str(summary.results), "steps": summary.steps,
                  "time_step": summary.time_step, "end_time": summary.end_time,
                  "wall_seconds": summary.wall_seconds, "particles": summary.particles,
                  "bonds": summary.bonds, "broken_bonds": summary.broken_bonds,
                  "frames": summary.frames,
                  "energy_budget": _budget(summary.energy)}
        if summary.profile is not None:
            report["profile"] = summary.profile
        if summary.stopped:
            report.update(stopped=summary.stopped, checkpoint=str(summary.checkpoint),
                          restart=restart)
        elif demo:
            from pdfem.post import load_results, summarize
            report["case"] = str(case.file)
            report["xdmf"] = str(summary.results.with_suffix(".xdmf"))
            report["post"] = summarize(load_results(summary.results))
        print(json.dumps(report))
    elif not args.quiet:
        print(summary.text())
        if demo and not summary.stopped:
            from pdfem.post import format_summary, load_results, summarize
            print()
            print(format_summary(summarize(load_results(summary.results))))
            print()
            print(f"Results: {summary.results} (HDF5); open "
                  f"{summary.results.with_suffix('.xdmf')} in ParaView.\n"
                  f"Plots: pdfem post {summary.results} --plots {out / 'plots'}")
    if not summary.stopped:
        return EXIT_OK
    print(f"pdfem: stopped by {summary.stopped} at t = {summary.end_time:.6e} s (step "
          f"{summary.steps:,}): checkpoint {summary.checkpoint}; {summary.results} holds "
          f"{summary.frames} frames, the last at the stop. Continue the run with\n  {restart}",
          file=sys.stderr, flush=True)
    return EXIT_STOPPED


def _restart_command(case_file, out: Path, checkpoint: Path | None, ranks: int) -> str:
    """The command line that continues a stopped run (on as many ranks; any count works)."""
    launch = f"mpiexec -n {ranks} " if ranks > 1 else ""
    return (f"{launch}pdfem run {shlex.quote(str(case_file))} --out {shlex.quote(str(out))} "
            f"--restart {shlex.quote(str(checkpoint))}")
