"""Compile time of the numba kernels: a few case files run a few steps with a cold and a warm cache.

Every kernel a run meets is compiled the first time (numba caches it on disk afterwards). This
runs five case files that together meet the pair loop with a plain critical stretch and with
the ice failure law (crushed bonds with friction), the full-family loop, short-range contact,
water, surface contact and an elastic structure, each shortened to two frames of 2 microseconds,
in a fresh process with an empty cache directory (cold), then again with the cache it filled
(warm). The child uses only ``load_case`` and ``run_case``, so the file can be run with an
older checkout's interpreter to compare (``OLD_VENV/bin/python benchmarks/compile_time.py``). Compile time = cold - warm CPU seconds of the child process (user + system).

    python -m pdfem.benchmarks.compile_time [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile

CASES = ["demo_ice_sheet_panel", "validation.ice_edge_crushing", "validation.sphere_ice_loops",
         "validation.floating_heave", "validation.lps_block_tension"]

CHILD = """
import dataclasses, sys, tempfile
from pathlib import Path
import pdfem.models
from pdfem.case.schema import load_case
from pdfem.run.driver import run_case
root = Path(list(pdfem.models.__path__)[0])
for key in sys.argv[1:]:
    path = root / (key.replace("validation.", "validation/") + ".toml")
    case = load_case(path)
    case = dataclasses.replace(case, run=dataclasses.replace(case.run, end_time=4e-6,
                                                             output_interval=2e-6))
    run_case(case, Path(tempfile.mkdtemp()) / path.stem, quiet=True)
"""


def _cpu(cache: str) -> float:
    """CPU seconds (user + system) of one child process running :data:`CASES` with ``cache``."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    env = dict(os.environ, NUMBA_CACHE_DIR=cache)
    subprocess.run([sys.executable, "-W", "ignore", "-c", CHILD, *CASES], env=env, check=True,
                   capture_output=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    cache = tempfile.mkdtemp(prefix="pdfem-numba-")
    cold = _cpu(cache)
    warm = _cpu(cache)
    out = {"cold_cpu_s": cold, "warm_cpu_s": warm, "compile_cpu_s": cold - warm, "cases": CASES}
    print(json.dumps(out) if args.json else
          f"cold {cold:.1f} s, warm {warm:.1f} s CPU: compile {cold - warm:.1f} s")


if __name__ == "__main__":
    main()
