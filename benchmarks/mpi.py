"""Strong scaling of the distributed PD step: ``mpiexec -n K python -m pdfem.benchmarks.mpi``.

A plate of about ``n`` particles (a cubic lattice 4 : 2 : 1 in x, y, z, horizon 3.015 dx, the
isotropic bond weights, no surface correction to keep the set-up short) is split over the ranks
by :func:`pdfem.parallel.partition.choose_partition`; every rank times ``steps`` steps (damage
on, nothing breaking) and the time spent in the two halo exchanges. Rank 0 prints one JSON
object: ranks, numba threads per rank, particles, unique pairs, seconds per step (the slowest
rank), exchange seconds per step, unique pair-steps per second, and the partition's largest halo.
Compare runs with 1 and 2 ranks (``NUMBA_NUM_THREADS=1`` for one core per rank).

``--contact``: the same plate cut into two layers at mid-thickness, two ice bodies, the upper
lowered by 0.15 dx so that the facing particles (one per column) press on each other, with
short-range contact on (:class:`pdfem.forces.short_range.ShortRangeContact`: every particle is
searched every step, and the interface holds n / nz interacting pairs, one per column). The
JSON then also gives the contact's seconds per step, its pairs, ghosts per rank, halo
refreshes and the median step (of the slowest rank per step; 20 steps), less sensitive to
other jobs on the machine.
"""

from __future__ import annotations

import argparse
import json
import time

import numba
import numpy as np

from pdfem.forces.short_range import ShortRangeContact
from pdfem.pd.body import IceBody
from pdfem.pd.materials.lps import IceMaterial
from pdfem.geometry.shapes import Box
from pdfem.parallel.comm import world
from pdfem.pd.layout.split import split_body
from pdfem.parallel.partition import choose_partition


DX = 0.01  # lattice spacing of the plates, m


def _layers(n: int) -> int:
    return max(1, round((n / 8) ** (1 / 3)))


def plate_body(n: int, z0: int = 0, z1: int | None = None, name: str = "plate") -> IceBody:
    """An unbreakable ice plate of about ``n`` particles, lattice 4 : 2 : 1 (dx = 1 cm); with
    ``z0``, ``z1`` only its lattice layers z0 .. z1 - 1."""
    nz = _layers(n)
    z1 = nz if z1 is None else z1
    shape = Box((0, 0, z0 * DX), (4 * nz * DX, 2 * nz * DX, z1 * DX))
    mat = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3)
    return IceBody.from_shape(name, shape, mat, DX, 3.015 * DX, surface_correction=False)


def strained(body: IceBody, drop: float = 0.0) -> IceBody:
    """``body`` under a uniform strain (every bond works), lowered by ``drop`` (m)."""
    body.y += 1e-4 * body.x0 * np.array([1.0, 0.5, 0.2])
    body.y[:, 2] -= drop
    return body


def _contact_steps(args, comm) -> dict:
    """The two-layer plate with short-range contact: figures of ``args.steps`` steps."""
    nz = _layers(args.n)
    half = max(1, nz // 2)
    bodies = [strained(plate_body(args.n, 0, half, "lower")),
              strained(plate_body(args.n, half, nz, "upper"), 0.15 * DX)]
    dists = []
    for b in bodies:
        owner, stats = choose_partition(b.x0, b.row_ptr, b.nbr, comm.size)
        dists.append(split_body(b, owner, comm))
    sr = ShortRangeContact(dists)
    dt = 1e-7

    def step():
        t0 = time.perf_counter()
        for d in dists:
            d.begin_step(dt)
            d.compute_forces()
        t = time.perf_counter()
        sr.add_forces()
        t1 = time.perf_counter()
        for d in dists:
            d.end_step(dt)
        return t1 - t, time.perf_counter() - t0

    for d in dists:
        d.start()
    sr.add_forces()
    step()  # warm-up
    for d in dists:
        d.layout.exchange_seconds = 0.0
    comm.allreduce_sum(0)
    t0 = time.perf_counter()
    times = np.array([step() for _ in range(args.steps)])
    wall = time.perf_counter() - t0
    pairs = sr.total_pairs()
    walls = comm.gather((wall, times[:, 0].sum(), sr.halo.n_ghosts, times[:, 1],
                         sum(d.layout.exchange_seconds for d in dists)))
    return {"walls": walls, "n_particles": sum(int(d.n_global) for d in dists),
            "n_pairs": sum(int(d.n_bonds) for d in dists),
            "contact_pairs": pairs, "refreshes": sr.halo.refreshes}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=1_000_000)
    ap.add_argument("--steps", type=int, default=10)
    ap.add_argument("--contact", action="store_true",
                    help="two plate layers pressed together, short-range contact on")
    args = ap.parse_args(argv)
    comm = world()
    if args.contact:
        res = _contact_steps(args, comm)
        if comm.rank == 0:
            walls = res.pop("walls")
            slowest = max(w[0] for w in walls) / args.steps
            per_step = np.max([w[3] for w in walls], axis=0)  # each step: its slowest rank
            print(json.dumps({"ranks": comm.size, "threads": numba.get_num_threads(), **res,
                              "step_s": slowest, "step_median_s": float(np.median(per_step)),
                              "contact_s": max(w[1] for w in walls) / args.steps,
                              "exchange_s": max(w[4] for w in walls) / args.steps,
                              "ghosts": [int(w[2]) for w in walls]}))
        return
    body = plate_body(args.n)
    body.y += 1e-4 * body.x0 * np.array([1.0, 0.5, 0.2])  # a uniform strain: every bond works
    owner, stats = choose_partition(body.x0, body.row_ptr, body.nbr, comm.size)
    dist = split_body(body, owner, comm)
    dist.start()
    dt = 1e-7
    dist.step(dt)  # warm-up
    dist.layout.exchange_seconds = 0.0
    comm.allreduce_sum(0)
    t0 = time.perf_counter()
    for _ in range(args.steps):
        dist.step(dt)
    wall = time.perf_counter() - t0
    walls = comm.gather((wall, dist.layout.exchange_seconds))
    if comm.rank == 0:
        slowest = max(w for w, _ in walls) / args.steps
        pairs = int(dist.n_bonds)
        print(json.dumps({"ranks": comm.size, "threads": numba.get_num_threads(),
                          "n_particles": int(dist.n_global), "n_pairs": pairs,
                          "step_s": slowest,
                          "exchange_s": max(e for _, e in walls) / args.steps,
                          "pair_steps_per_s": pairs / slowest,
                          "partition": stats.name, "halo_max": int(stats.halo.max())}))


def bench_mpi(n: int = 1_000_000, ranks=(1, 2), steps: int | None = None,
              contact: bool = False) -> dict:
    """Run :func:`main` under ``mpiexec -n K`` for each K (one numba thread per rank) and
    collect the figures, with the speed-up of each K over one rank (``pdfem bench mpi``;
    ``contact``: the two-layer plate with short-range contact, ``--contact``)."""
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
    steps = (20 if contact else 10) if steps is None else steps
    runs = []
    for k in ranks:
        # this file by path, not ``-m``: run from a checkout, ``-m`` would import the
        # checkout's pdfem, which has no pdfem.benchmarks (only the installed package has)
        out = subprocess.run([mpiexec, "-n", str(k), sys.executable, str(Path(__file__).resolve()),
                              "--n", str(n), "--steps", str(steps)]
                             + (["--contact"] if contact else []), env=env, check=True,
                             capture_output=True, text=True)
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    base = runs[0]["step_s"]
    for r in runs:
        r["speedup"] = base / r["step_s"]
        if contact:  # the median step is less sensitive to other jobs on the machine
            r["speedup_median"] = runs[0]["step_median_s"] / r["step_median_s"]
    return {"n_particles": runs[0]["n_particles"], "n_pairs": runs[0]["n_pairs"],
            "contact": contact, "load_average": os.getloadavg()[0], "runs": runs}


if __name__ == "__main__":
    main()
