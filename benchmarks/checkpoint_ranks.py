"""Cost of per-rank checkpoints (issue 17, item 3): write time, part sizes, restore time and
peak memory per rank, on K ranks and restarted on K and on 1 rank.

The case is the cylinder-and-plate case of tests/run/test_mpi_run.py refined to ``--dx`` (0.005 m:
160,000 particles, about 10 M bonds), run for 1.5e-4 s with a checkpoint every 20 coupling
steps. Every ``write_checkpoint`` and the restart's ``restore`` are timed on every rank (s);
each process's peak resident set (MB, ``ru_maxrss``) is reported. Wall times depend on the
machine's load; sizes do not.

Usage: mpiexec -n 2 python benchmarks/checkpoint_ranks.py OUT [--dx 0.005]
       (then, for the restarts, the same with ``--restart 2`` under mpiexec -n 2, and
       ``--restart 1`` without mpiexec)
"""

from __future__ import annotations

import argparse
import json
import resource
import shutil
import time
from pathlib import Path

CASE = """
[run]
end_time = 1.5e-4
output_interval = 1.5e-4
checkpoint_interval_steps = 20
checkpoint_interval_minutes = 0
energy_tolerance = 0.1
[[ice]]
name = "plate"
dx = {dx}
shape = {{ box = {{ min = [0.0, 0.0, 0.0], max = [1.0, 0.5, 0.04] }} }}
material = {{ density = 900.0, youngs_modulus = 4.1e9, poisson_ratio = 0.3, fracture_energy = 3.0 }}
[[structure]]
name = "cylinder"
kind = "rigid"
mesh = "indenters"
params = {{ shape = "cylinder", radius = 0.1, length = 0.1, axis = "z", center_x = 0.5, center_y = 0.6005, center_z = 0.02, element_size = 0.02 }}
motion = {{ velocity = [0.0, -4.0, 0.0] }}
"""


def main() -> None:
    """Run the write or a restart and print one JSON line (rank 0)."""
    from pdfem.case.schema import load_case
    from pdfem.parallel.comm import world
    from pdfem.run import driver, loop

    ap = argparse.ArgumentParser()
    ap.add_argument("out", type=Path)
    ap.add_argument("--dx", type=float, default=0.005)
    ap.add_argument("--restart", type=int, default=0, help="restart the written run on this "
                    "many ranks (0: write it)")
    args = ap.parse_args()
    comm = world()
    args.out.mkdir(parents=True, exist_ok=True)
    if comm.rank == 0:
        (args.out / "case.toml").write_text(CASE.format(dx=args.dx))
    comm.bcast(0)
    case = load_case(args.out / "case.toml")
    seconds: list[float] = []

    def timed(fn):
        def wrapper(*a, **k):
            t = time.perf_counter()
            out = fn(*a, **k)
            seconds.append(round(time.perf_counter() - t, 3))
            return out
        return wrapper

    loop.write_checkpoint, driver.restore = timed(loop.write_checkpoint), timed(driver.restore)
    run = args.out / "run"
    if args.restart:
        again = args.out / f"restart{args.restart}"
        if comm.rank == 0:
            shutil.rmtree(again, ignore_errors=True)
            shutil.copytree(run, again)
        comm.bcast(0)
        driver.run_case(case, again, quiet=True, comm=comm, restart=again / "checkpoint.h5")
    else:
        driver.run_case(case, run, quiet=True, comm=comm)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    figures = comm.allgather((seconds, round(peak)))
    if comm.rank == 0:
        sizes = {p.name: p.stat().st_size for p in sorted(run.glob("checkpoint*.h5"))}
        print(json.dumps({"ranks": comm.size, "restart": args.restart,
                          "seconds_per_rank": [f[0] for f in figures],
                          "peak_mb_per_rank": [f[1] for f in figures], "files": sizes}))


if __name__ == "__main__":
    main()
