"""Strong scaling of the distributed PD step: ``mpiexec -n K python -m pdfem.benchmarks.mpi``.

A plate of about ``n`` particles (a cubic lattice 4 : 2 : 1 in x, y, z, horizon 3.015 dx, the
isotropic bond weights, no surface correction to keep the set-up short) is split over the ranks
by :func:`pdfem.parallel.partition.choose_partition`; every rank times ``steps`` steps (damage
on, nothing breaking) and the time spent in the two halo exchanges. Rank 0 prints one JSON
object: ranks, numba threads per rank, particles, unique pairs, seconds per step (the slowest
rank), exchange seconds per step, unique pair-steps per second, and the partition's largest halo.
Compare runs with 1 and 2 ranks (``NUMBA_NUM_THREADS=1`` for one core per rank).
"""

from __future__ import annotations

import argparse
import json
import time

import numba
import numpy as np

from pdfem.pd.body import IceBody
from pdfem.pd.materials.lps import IceMaterial
from pdfem.geometry.shapes import Box
from pdfem.parallel.comm import world
from pdfem.pd.distributed import DistributedIce
from pdfem.parallel.partition import choose_partition


def plate_body(n: int) -> IceBody:
    """An unbreakable ice plate of about ``n`` particles, lattice 4 : 2 : 1 (dx = 1 cm)."""
    dx = 0.01
    nz = max(1, round((n / 8) ** (1 / 3)))
    shape = Box((0, 0, 0), (4 * nz * dx, 2 * nz * dx, nz * dx))
    mat = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3)
    return IceBody.from_shape("plate", shape, mat, dx, 3.015 * dx, surface_correction=False)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--steps", type=int, default=10)
    args = ap.parse_args(argv)
    comm = world()
    body = plate_body(args.n)
    body.y += 1e-4 * body.x0 * np.array([1.0, 0.5, 0.2])  # a uniform strain: every bond works
    owner, stats = choose_partition(body.x0, body.row_ptr, body.nbr, comm.size)
    dist = DistributedIce(body, owner, comm)
    dist.start()
    dt = 1e-7
    dist.step(dt)  # warm-up
    dist.exchange_seconds = 0.0
    comm.allreduce_sum(0)
    t0 = time.perf_counter()
    for _ in range(args.steps):
        dist.step(dt)
    wall = time.perf_counter() - t0
    walls = comm.gather((wall, dist.exchange_seconds))
    if comm.rank == 0:
        slowest = max(w for w, _ in walls) / args.steps
        pairs = int(dist.global_body.nbr.shape[0])
        print(json.dumps({"ranks": comm.size, "threads": numba.get_num_threads(),
                          "n_particles": int(dist.global_n), "n_pairs": pairs,
                          "step_s": slowest,
                          "exchange_s": max(e for _, e in walls) / args.steps,
                          "pair_steps_per_s": pairs / slowest,
                          "partition": stats.name, "halo_max": int(stats.halo.max())}))


def bench_mpi(n: int = 1_000_000, ranks=(1, 2), steps: int = 10) -> dict:
    """Run :func:`main` under ``mpiexec -n K`` for each K (one numba thread per rank) and
    collect the figures, with the speed-up of each K over one rank (``pdfem bench mpi``)."""
    import os
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    here = Path(sys.executable).parent / "mpiexec"
    mpiexec = str(here) if here.exists() else shutil.which("mpiexec")
    if mpiexec is None:
        raise RuntimeError("no mpiexec found (pip install mpich)")
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    runs = []
    for k in ranks:
        # this file by path, not ``-m``: run from a checkout, ``-m`` would import the
        # checkout's pdfem, which has no pdfem.benchmarks (only the installed package has)
        out = subprocess.run([mpiexec, "-n", str(k), sys.executable, str(Path(__file__).resolve()),
                              "--n", str(n), "--steps", str(steps)], env=env, check=True,
                             capture_output=True, text=True)
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    base = runs[0]["step_s"]
    for r in runs:
        r["speedup"] = base / r["step_s"]
    return {"n_particles": runs[0]["n_particles"], "n_pairs": runs[0]["n_pairs"],
            "load_average": os.getloadavg()[0], "runs": runs}


if __name__ == "__main__":
    main()
