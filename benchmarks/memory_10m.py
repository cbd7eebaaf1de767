"""Peak memory and time of a large PD-only run: set-up (lattice, search, weights, surface
correction) and a few steps of an ice block, measured with resource.getrusage.

Usage: python benchmarks/memory_10m.py [--n 10000000] [--steps 3] [--lean]

``--lean`` builds the workspace without the bond-length scratch of the fused step (8 bytes per
pair less, one more square root per bond). Prints one JSON object: particles, pairs, the peak
resident set size after set-up and after the steps (bytes), bytes per pair and per particle of
the stored arrays, times, load averages.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import time

import numba
import numpy as np

from pdfem.pd.bonds import kernels as kn
from pdfem.pd.body import IceBody
from pdfem.geometry.lattice import lattice_points
from pdfem.pd.materials.lps import SEA_ICE_DEFAULTS, IceMaterial


def peak_rss() -> int:
    """Peak resident set size of this process so far, bytes (Linux reports KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--n", type=int, default=10_000_000)
    ap.add_argument("--steps", type=int, default=3)
    ap.add_argument("--lean", action="store_true")
    args = ap.parse_args()
    dx = 0.01
    side = round(args.n ** (1 / 3))
    d = SEA_ICE_DEFAULTS
    ice = IceMaterial(d["density"], d["youngs_modulus"], d["poisson_ratio"],
                      fracture_energy=d["fracture_energy"])
    load0 = os.getloadavg()[0]
    # compile / load every kernel on a tiny block first (not part of the figures)
    tiny = IceBody.from_points("tiny", lattice_points(np.zeros(3), np.full(3, 8 * dx), dx), ice,
                               dx, 3.015 * dx, isotropic=True, surface_correction=True)
    tiny.start()
    tiny.step(1e-7)
    t0 = time.perf_counter()
    x = lattice_points(np.zeros(3), np.full(3, side * dx), dx)
    body = IceBody.from_points("block", x, ice, dx, 3.015 * dx, isotropic=True,
                               surface_correction=True, keep_bond_length=not args.lean)
    del x
    t_setup = time.perf_counter() - t0
    rss_setup = peak_rss()
    dt = 0.5 * body.stable_time_step()
    body.v[:, 0] = 0.1 * np.sin(np.pi * body.x0[:, 1] / (side * dx))  # a shear wave
    body.start()
    t1 = time.perf_counter()
    for _ in range(args.steps):
        body.step(dt)
    t_step = (time.perf_counter() - t1) / args.steps
    n, p = body.n, body.n_bonds
    stored_pair = body.nbr.itemsize + body.xi_len.itemsize + body.weight.itemsize
    print(json.dumps({
        "n_particles": n, "n_pairs": p, "threads": numba.get_num_threads(), "lean": args.lean,
        "setup_s": t_setup, "step_s": t_step, "steps": args.steps,
        "peak_rss_after_setup": rss_setup, "peak_rss_after_steps": peak_rss(),
        "stored_bytes_per_pair": stored_pair,
        "scratch_bytes_per_pair": 0 if args.lean else 8,
        "peak_rss_per_pair": peak_rss() / p,
        "load_average": load0, "load_average_after": os.getloadavg()[0],
    }))


if __name__ == "__main__":
    main()
