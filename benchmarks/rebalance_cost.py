"""Cost of one re-partition of a split ice body (issue 17, item 5): RCB and migration.

A block of about ``--n`` particles (dx = 0.01 m, delta = 3.015 dx) is built by the distributed
set-up on the ranks of ``mpiexec -n K`` and its forces computed. Then, each timed on every rank
(the largest over ranks is reported):

1. one velocity-Verlet step, for scale;
2. a re-partition on the set-up's own positions (:meth:`IceBody.rebalance`: weighted RCB
   plus migration; few particles change owner);
3. the block turned rigidly by 90 degrees about z (the current positions only), so that the
   bisection cuts across another axis and about half the particles change owner, then a
   re-partition (the worst case: a migration of about half the body);
4. one step after it.

Usage: mpiexec -n 2 python benchmarks/rebalance_cost.py [--n 1000000]

Prints one JSON object (seconds, particles moved, peak resident set per rank in GB). Run with
NUMBA_NUM_THREADS=1 and OPENBLAS_NUM_THREADS=1 in the environment.
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np


def _vm_hwm() -> float:
    """Peak resident set size of this process so far (GB), from /proc/self/status."""
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) * 1024 for line in f if line.startswith("VmHWM")) / 1e9


def main() -> None:
    from pdfem.geometry.shapes import Box
    from pdfem.parallel.comm import world
    from pdfem.pd.body import IceBody
    from pdfem.pd.materials.lps import IceMaterial

    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=1_000_000)
    a = ap.parse_args()
    comm = world()
    dx = 0.01
    side = round(a.n ** (1 / 3))
    mat = IceMaterial(density=900.0, youngs_modulus=4e9, poisson_ratio=0.3, fracture_energy=1.0)
    box = Box((0, 0, 0), (side * dx, side * dx, side * dx))
    t0 = time.perf_counter()
    ice = IceBody.from_shape("block", box, mat, dx, 3.015 * dx, comm=comm)
    ice.start()
    setup = time.perf_counter() - t0
    dt = 0.8 * ice.stable_time_step()
    out = {"ranks": comm.size, "particles": ice.n_global, "bonds": ice.n_bonds,
           "setup_s": setup}

    def timed(fn) -> float:
        comm.allreduce_sum(0)
        t = time.perf_counter()
        fn()
        return max(comm.allgather(time.perf_counter() - t))

    def owned_gids() -> set:
        return set(ice.layout.gid[ice.layout.owned].tolist())

    out["step_s"] = timed(lambda: ice.step(dt))
    out["peak_rss_before_gb"] = max(comm.allgather(_vm_hwm()))
    out["imbalance_setup"] = ice.imbalance()
    before = owned_gids()
    out["rebalance_in_place_s"] = timed(ice.rebalance)
    out["moved_in_place"] = int(comm.allreduce_sum(len(owned_gids() - before)))
    out["imbalance_after_in_place"] = ice.imbalance()
    c = 0.5 * side * dx
    b = ice
    b.y[:] = np.stack([c - (b.y[:, 1] - c), c + (b.y[:, 0] - c), b.y[:, 2]], axis=1)
    before = owned_gids()
    out["rebalance_turned_s"] = timed(ice.rebalance)
    out["moved_turned"] = int(comm.allreduce_sum(len(owned_gids() - before)))
    out["imbalance_after_turned"] = ice.imbalance()
    out["step_after_s"] = timed(lambda: ice.step(dt))
    out["peak_rss_gb"] = max(comm.allgather(_vm_hwm()))
    if comm.rank == 0:
        print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
