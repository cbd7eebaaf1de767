"""The ``pdfem`` command line.

    pdfem run [CASE.toml] [--out DIR] [--restart CHECKPOINT] [--quiet] [--json]
    pdfem post RESULTS.h5 [--plots DIR] [--csv FILE] [--json]
    pdfem mesh MODEL [--set key=value ...] [-o FILE.msh] [--json]
    pdfem bench {search,step,mpi,partition} [--n N] [--json]
    pdfem info [--json]
    pdfem --version

``pdfem run CASE --restart DIR/checkpoint.h5`` continues a run of CASE from its last checkpoint,
appending to the results file in DIR (``--out`` defaults to the checkpoint's directory).

``pdfem run`` without a case runs the built-in demo (``demo_ice_sheet_panel.toml`` of the
package ``pdfem.models``) into ``results/demo_ice_sheet_panel/`` and prints its post summary.

Exit status: 0 success, 2 bad input (the message names file and field), 3 a run stopped by a
detected instability, 1 anything else. With ``--json`` standard output holds exactly one JSON
object and nothing else.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.resources
import io
import json
import platform
import sys
import traceback
import warnings
from pathlib import Path

from . import __version__
from .errors import EXIT_BAD_INPUT, EXIT_FAILURE, EXIT_INSTABILITY, EXIT_OK, InputError, InstabilityError

DEMO_CASE = "demo_ice_sheet_panel.toml"
"""The built-in demo case (package data of ``pdfem.models``) that ``pdfem run`` runs without a case."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str):  # argparse's own errors are bad input too: exit 2, no traceback
        self.print_usage(sys.stderr)
        raise InputError(None, None, f"{self.prog}: {message}")


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="pdfem", description="Ice loads on structures: peridynamic ice, finite-element structures. SI units.")
    p.add_argument("--version", action="version", version=f"pdfem {__version__}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    r = sub.add_parser("run", help="run a case file (no case: the built-in demo)")
    r.add_argument("case", nargs="?", default=None,
                   help=f"case file (TOML, SI units); default: the demo {DEMO_CASE}")
    r.add_argument("--out", default=None, help="output directory (default: results/<case name>)")
    r.add_argument("--restart", default=None, metavar="CHECKPOINT",
                   help="continue the run of CASE from this checkpoint (checkpoint.h5 in the "
                        "run's output directory), appending to its results")
    r.add_argument("--quiet", action="store_true", help="no progress or messages")
    r.add_argument("--json", action="store_true", help="print the run summary as one JSON object")

    q = sub.add_parser("post", help="summarise a results file: table, plots, CSV")
    q.add_argument("results", help="results file (results.h5 written by 'pdfem run')")
    q.add_argument("--plots", default=None, metavar="DIR", help="write PNG plots into DIR")
    q.add_argument("--csv", default=None, metavar="FILE",
                   help="write the per-step load and monitor histories to FILE (CSV)")
    q.add_argument("--json", action="store_true", help="print the summary as one JSON object")

    m = sub.add_parser("mesh", help="mesh a model of models/ (or a .py file) with gmsh")
    m.add_argument("model", help="model name (hull_panel, propeller_blade, indenters) or a .py file with build()")
    m.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="model parameter (SI units), repeatable")
    m.add_argument("-o", "--output", default=None, help="output .msh file (default: <model>.msh)")
    m.add_argument("--json", action="store_true", help="print the mesh report as one JSON object")

    b = sub.add_parser("bench", help="performance measurements (not tests)")
    b.add_argument("what", choices=["search", "step", "mpi", "partition"],
                   help="search, step, mpi (strong scaling on 1 and 2 ranks), partition (the "
                        "partition model of the 1.44M-particle plate, 2-64 ranks)")
    b.add_argument("--n", type=int, default=1_000_000, help="number of particles (default 1,000,000)")
    b.add_argument("--json", action="store_true", help="print one JSON object")

    i = sub.add_parser("info", help="versions, threads and MPI")
    i.add_argument("--json", action="store_true", help="print one JSON object")
    return p


def _info() -> dict:
    import numba
    out = {"pdfem": __version__, "python": platform.python_version(), "platform": platform.platform(),
           "numba_threads": numba.get_num_threads()}
    for mod in ("numpy", "scipy", "numba", "h5py", "meshio", "skfem", "gmsh", "matplotlib", "mpi4py"):
        try:
            m = __import__(mod)
            out[mod] = getattr(m, "__version__", "installed")
        except Exception as exc:  # an optional part that does not import is reported, not fatal
            out[mod] = f"unavailable ({type(exc).__name__}: {exc})"
    try:
        from mpi4py import MPI
        out["mpi_library"] = MPI.Get_library_version().splitlines()[0].strip()
    except Exception as exc:
        out["mpi_library"] = f"unavailable ({type(exc).__name__})"
    return out


def demo_case_file() -> contextlib.AbstractContextManager[Path]:
    """The built-in demo case, a file of the package ``pdfem.models``, as a context manager
    giving its path on disk."""
    return importlib.resources.as_file(importlib.resources.files("pdfem.models") / DEMO_CASE)


def _cmd_run(args) -> int:
    from .config import load_case
    from .driver import run_case
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
    from .comm import run_guarded, world
    comm = world()  # under mpiexec: every rank runs, rank 0 writes and reports
    if comm.size > 1:
        from .parallel import warm_before_ranks
        run_guarded(warm_before_ranks, comm, comm=comm)  # one rank fills numba's cache first
    if args.json:
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            summary = run_guarded(run_case, case, out, quiet=True, restart=args.restart,
                                  comm=comm)
        if comm.rank != 0:
            return EXIT_OK
        report = {"results": str(summary.results), "steps": summary.steps,
                  "time_step": summary.time_step, "end_time": summary.end_time,
                  "wall_seconds": summary.wall_seconds, "particles": summary.particles,
                  "bonds": summary.bonds, "broken_bonds": summary.broken_bonds,
                  "frames": summary.frames}
        if demo:
            from .post import load_results, summarize
            report["case"] = str(case.file)
            report["xdmf"] = str(summary.results.with_suffix(".xdmf"))
            report["post"] = summarize(load_results(summary.results))
        print(json.dumps(report))
    else:
        summary = run_guarded(run_case, case, out, quiet=args.quiet, restart=args.restart,
                              comm=comm)
        if not args.quiet and comm.rank == 0:
            print(summary.text())
            if demo:
                from .post import format_summary, load_results, summarize
                print()
                print(format_summary(summarize(load_results(summary.results))))
                print()
                print(f"Results: {summary.results} (HDF5); open "
                      f"{summary.results.with_suffix('.xdmf')} in ParaView.\n"
                      f"Plots: pdfem post {summary.results} --plots {out / 'plots'}")
    return EXIT_OK


def _cmd_post(args) -> int:
    from .post import format_summary, load_results, summarize, write_csv
    from .post_plots import write_plots
    results = load_results(args.results)
    summary = summarize(results)
    written: list[str] = []
    if args.csv:
        try:
            write_csv(results, args.csv)
        except OSError as exc:
            raise InputError(args.csv, "--csv", f"cannot write the CSV file ({exc})") from None
        summary["csv"] = args.csv
    if args.plots:
        try:
            written = [str(p) for p in write_plots(results, args.plots)]
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


def _cmd_mesh(args) -> int:
    from .meshing import mesh_model, parse_set
    report = mesh_model(args.model, parse_set(args.set), Path(args.output) if args.output else None)
    print(json.dumps(report.as_dict()) if args.json else report.text())
    return EXIT_OK


def _cmd_bench(args) -> int:
    if args.n < 8:
        raise InputError(None, "--n", "the benchmark needs at least 8 particles", args.n)
    if args.what == "search":
        from .benchmarks.search import bench_search as fn
    elif args.what == "step":
        from .benchmarks.step import bench_step as fn
    elif args.what == "mpi":
        from .benchmarks.mpi import bench_mpi as fn
    else:
        from .benchmarks.partition_model import partition_model

        def fn(n):  # the seed's plate; n is not used
            return partition_model()
    res = fn(n=args.n)
    if args.json:
        print(json.dumps(res))
    else:
        for k, v in res.items():
            print(f"{k:>32}: {v}")
    return EXIT_OK


def _cmd_info(args) -> int:
    info = _info()
    if args.json:
        print(json.dumps(info))
    else:
        for k, v in info.items():
            print(f"{k:>14}: {v}")
    return EXIT_OK


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``pdfem`` console script; returns the exit status."""
    try:
        args = _parser().parse_args(argv)
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            warnings.showwarning = lambda msg, *a, **k: print(f"warning: {msg}", file=sys.stderr)
            return {"run": _cmd_run, "post": _cmd_post, "mesh": _cmd_mesh, "bench": _cmd_bench,
                    "info": _cmd_info}[args.command](args)
    except InputError as exc:
        print(exc.text(), file=sys.stderr)
        return EXIT_BAD_INPUT
    except InstabilityError as exc:
        print(f"Run stopped: {exc}", file=sys.stderr)
        return EXIT_INSTABILITY
    except KeyboardInterrupt:
        print("interrupted; results written so far are kept", file=sys.stderr)
        return EXIT_FAILURE
    except SystemExit as exc:  # --help / --version
        return int(exc.code or 0) if isinstance(exc.code, int) else EXIT_OK
    except Exception:
        traceback.print_exc()
        print("pdfem: an internal error stopped the run (exit 1); results written so far are kept.",
              file=sys.stderr)
        return EXIT_FAILURE


def _entry() -> None:  # pragma: no cover
    sys.exit(main())


if __name__ == "__main__":  # pragma: no cover
    _entry()
