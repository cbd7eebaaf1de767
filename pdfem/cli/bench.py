"""``pdfem bench {search,step,mpi,partition,structure,output} [--n N] [--contact] [--json]``:
performance figures.

The benchmark code (the package ``pdfem.benchmarks``) is imported only when this command runs.
"""

from __future__ import annotations

import argparse
import json

from pdfem.errors import EXIT_OK, InputError

NAME = "bench"
HELP = "performance measurements (not tests)"


def add_arguments(b: argparse.ArgumentParser) -> None:
    """The options of ``pdfem bench``."""
    b.add_argument("what", choices=["search", "step", "mpi", "partition", "structure", "output"],
                   help="search, step, mpi (strong scaling on 1 and 2 ranks), partition (the "
                        "partition model of the 1.44M-particle plate, 2-64 ranks), structure "
                        "(the demo panel's FE cost per coupling step), output (the results writer: "
                        "frame 100 against frame 10,000, --n particles, default 200)")
    b.add_argument("--n", type=int, default=1_000_000, help="number of particles (default 1,000,000)")
    b.add_argument("--contact", action="store_true",
                   help="mpi only: the plate in two layers pressed together, short-range contact "
                        "on (benchmarks/mpi.py)")
    b.add_argument("--json", action="store_true", help="print one JSON object")


def run(args: argparse.Namespace) -> int:
    """Run the benchmark; exit status."""
    if args.n < 8:
        raise InputError(None, "--n", "the benchmark needs at least 8 particles", args.n)
    if args.what == "search":
        from pdfem.benchmarks.search import bench_search as fn
    elif args.what == "step":
        from pdfem.benchmarks.step import bench_step as fn
    elif args.what == "mpi":
        from pdfem.benchmarks.mpi import bench_mpi

        def fn(n):
            return bench_mpi(n=n, contact=args.contact)
    elif args.what == "partition":
        from pdfem.benchmarks.partition_model import partition_model

        def fn(n):  # the seed's plate; n is not used
            return partition_model()
    elif args.what == "output":
        from pdfem.benchmarks.output_frames import bench_output_frames as fn
        if args.n == 1_000_000:
            args.n = 200
    else:
        from pdfem.benchmarks.structure_step import bench_structure_step

        def fn(n):  # the demo's panel; n is not used
            return bench_structure_step()
    res = fn(n=args.n)
    if args.json:
        print(json.dumps(res))
    else:
        for k, v in res.items():
            print(f"{k:>32}: {v}")
    return EXIT_OK


