"""Peak memory per rank of an ice-only run on 1, 2 and 4 MPI ranks (issue 17, done-when).

A block of about ``--n`` particles (dx = 0.01 m, delta = 3.015 dx, cubic influence function and
surface correction) is set up and advanced ``--steps`` velocity-Verlet steps: serially as a
whole :class:`~pdfem.pd.body.IceBody` (``from_shape``), and on K ranks by the distributed set-up
(:mod:`pdfem.pd.layout.setup`), each rank building only its part. Every process reports
its peak resident set size (VmHWM of /proc/self/status, bytes), gathered to rank 0; the
figures are the largest per rank, and their ratios to the serial run's.

Usage: python benchmarks/memory_ranks.py [--n 2000000] [--steps 3] [--ranks 1 2 4]

Runs each configuration as a subprocess (``mpiexec -n K`` for K > 1) with NUMBA_NUM_THREADS=1
and prints one JSON object. Every process first compiles or loads the kernels on a tiny block
(in its figure, as in a real run).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path


def vm_hwm() -> int:
    """Peak resident set size of this process so far (bytes), from /proc/self/status."""
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmHWM"))


def worker(n: int, steps: int) -> None:
    """One configuration: the serial body (one process) or the distributed set-up (MPI)."""
    import numpy as np

    from pdfem.geometry.shapes import Box
    from pdfem.parallel.comm import world
    from pdfem.pd.body import IceBody
    from pdfem.pd.materials.lps import SEA_ICE_DEFAULTS, IceMaterial
    from pdfem.run.parallel import warm_before_ranks

    comm = world()
    d = SEA_ICE_DEFAULTS
    mat = IceMaterial(d["density"], d["youngs_modulus"], d["poisson_ratio"],
                      fracture_energy=d["fracture_energy"])
    dx = 0.01
    side = round(n ** (1 / 3))
    shape = Box((0, 0, 0), (side * dx, side * dx, side * dx))
    tiny = IceBody.from_shape("tiny", Box((0, 0, 0), (8 * dx,) * 3), mat, dx, 3.015 * dx)
    tiny.start()
    tiny.step(1e-7)
    warm_before_ranks(comm)
    t0 = time.perf_counter()
    body = IceBody.from_shape("block", shape, mat, dx, 3.015 * dx, comm=comm)
    total = body.n_global
    t_setup = time.perf_counter() - t0
    rss_setup = vm_hwm()
    dt = 0.5 * body.stable_time_step()
    body.v[:, 0] = 0.1 * np.sin(np.pi * body.x0[:, 1] / (side * dx))  # a shear wave
    body.start()
    t1 = time.perf_counter()
    for _ in range(steps):
        body.step(dt)
    t_step = (time.perf_counter() - t1) / steps
    figures = comm.gather((rss_setup, vm_hwm(), int(body.n)))
    if comm.rank == 0:
        print("RESULT " + json.dumps({
            "ranks": comm.size, "particles": int(total), "setup_s": t_setup, "step_s": t_step,
            "peak_rss_setup_per_rank": [f[0] for f in figures],
            "peak_rss_per_rank": [f[1] for f in figures],
            "local_particles_per_rank": [f[2] for f in figures]}))


def run(ranks: int, n: int, steps: int) -> dict:
    """Run one configuration in a subprocess and return its figures."""
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", "--n", str(n),
           "--steps", str(steps)]
    if ranks > 1:
        here = Path(sys.executable).parent / "mpiexec"
        cmd = [str(here) if here.exists() else shutil.which("mpiexec"), "-n", str(ranks)] + cmd
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    r = subprocess.run(cmd, capture_output=True, text=True, env=env, check=True)
    line = next(ln for ln in r.stdout.splitlines() if ln.startswith("RESULT "))
    return json.loads(line[len("RESULT "):])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--n", type=int, default=2_000_000)
    ap.add_argument("--steps", type=int, default=3)
    ap.add_argument("--ranks", type=int, nargs="+", default=[1, 2, 4])
    ap.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        worker(args.n, args.steps)
        return
    load0 = os.getloadavg()[0]
    runs = {k: run(k, args.n, args.steps) for k in args.ranks}
    serial = max(runs[min(runs)]["peak_rss_per_rank"])
    out = {"runs": runs, "load_average": load0, "load_average_after": os.getloadavg()[0],
           "peak_per_rank_over_serial": {k: max(r["peak_rss_per_rank"]) / serial
                                         for k, r in runs.items()}}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
