"""Peak memory per rank of ``pdfem run`` itself, serially and on MPI ranks (issue 17, done-when).

Runs the case ``benchmarks/memory_box_2m.toml`` (a 126^3 ice box, 2,000,376 particles, dx = 1 cm,
``output_per_rank``, a few steps and three frames) through the command line as a user would:
``/usr/bin/time -v pdfem run CASE --out DIR --quiet`` in one process, then ``mpiexec -n K
/usr/bin/time -v pdfem run ...`` so that every rank reports its own "Maximum resident set
size". Unlike benchmarks/memory_ranks.py this includes the CLI's pre-flight estimate, the run's
set-up (regions, reference, contact checks), the output files and frames. Numba's threads are
left at their default (NUMBA_NUM_THREADS is passed through as it is set, or not).

Usage: python benchmarks/memory_cli.py [--side 126] [--ranks 1 2] [--keep DIR]

``--side`` other than 126 scales the box (side^3 particles) for quick looks. A tiny run of
each configuration first fills numba's cache so that no measured process compiles. Prints one
JSON object: the max RSS of every process per configuration (bytes), the largest per rank over
the serial run's, the load average before and after.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

CASE = Path(__file__).resolve().with_name("memory_box_2m.toml")


def case_text(side: int) -> str:
    """The case file with a box of ``side`` lattice points a side (dx = 1 cm)."""
    text = CASE.read_text()
    if side != 126:
        edge = f"{side * 0.01:.2f}"
        text = text.replace("max = [1.26, 1.26, 1.26]", f"max = [{edge}, {edge}, {edge}]")
        text = text.replace("max = [1.261, 1.261, 0.006]", f"max = [{edge}1, {edge}1, 0.006]")
    return text


def pdfem_command() -> list[str]:
    """``pdfem`` of this environment (the console script beside this Python, else ``-m``)."""
    here = Path(sys.executable).parent / "pdfem"
    return [str(here)] if here.exists() else [sys.executable, "-m", "pdfem"]


def mpiexec() -> str:
    """``mpiexec`` beside this Python (the mpich wheel's), else the one on PATH."""
    here = Path(sys.executable).parent / "mpiexec"
    return str(here) if here.exists() else shutil.which("mpiexec")


def run(case: Path, out: Path, ranks: int) -> dict:
    """``pdfem run`` of ``case`` on ``ranks`` processes under /usr/bin/time -v: the max RSS of
    each process (bytes) and the wall time (s) of the slowest."""
    shutil.rmtree(out, ignore_errors=True)
    cmd = ["/usr/bin/time", "-v", *pdfem_command(), "run", str(case), "--out", str(out),
           "--quiet"]
    if ranks > 1:
        cmd = [mpiexec(), "-n", str(ranks), *cmd]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stderr[-3000:]}")
    rss = [int(v) * 1024 for v in re.findall(r"Maximum resident set size \(kbytes\): (\d+)",
                                              r.stderr)]
    wall = re.findall(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (\S+)", r.stderr)
    return {"ranks": ranks, "command": " ".join(cmd), "max_rss_per_process": rss,
            "wall": wall}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--side", type=int, default=126)
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--keep", type=Path, default=None,
                    help="write the case and the runs' output here (default: a temporary dir)")
    args = ap.parse_args()
    work = args.keep or Path(tempfile.mkdtemp(prefix="pdfem_memory_cli_"))
    work.mkdir(parents=True, exist_ok=True)
    case = work / "case.toml"
    case.write_text(case_text(args.side))
    (work / "warm.toml").write_text(case_text(12))
    for k in args.ranks:  # numba's cache filled by a tiny run of each configuration
        run(work / "warm.toml", work / f"warm{k}", k)
    load0 = os.getloadavg()[0]
    runs = {k: run(case, work / f"run{k}", k) for k in args.ranks}
    serial = max(runs[min(runs)]["max_rss_per_process"])
    out = {"side": args.side, "particles": args.side ** 3, "runs": runs,
           "load_average": load0, "load_average_after": os.getloadavg()[0],
           "max_rss_per_rank_over_serial": {k: max(r["max_rss_per_process"]) / serial
                                            for k, r in runs.items()}}
    if args.keep is None:
        shutil.rmtree(work, ignore_errors=True)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
