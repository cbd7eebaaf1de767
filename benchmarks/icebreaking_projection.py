"""The icebreaking case on 16-64 MPI ranks: a projection from the partition model.

``python -m pdfem.benchmarks.icebreaking_projection [--json]`` (a second; no MPI). For the level-ice
sheet of ``models/icebreaker_level_ice.toml`` (a lattice of 105 x 90 x 3 particles) and the same
sheet refined 2x and 4x (2x, 4x the particles per axis; the steps grow with them), it splits one
coupled step into the three parts a profile of the tiny case shows (``python -m cProfile -m pdfem
run`` on ``models/validation/icebreaker_tiny.toml``, 0.2 s, BENCHMARKS.md):

- **bond work** (dilatation and forces, :data:`BOND_SHARE` of the step on one rank): on P ranks
  the largest rank's bonds (:func:`pdfem.run.estimates.best_split`, exact lattice counts) over
  all bonds, plus the halo exchange of :mod:`pdfem.benchmarks.scaling_model`;
- **per-particle work** (contact with the hull, short-range search, water, impulses:
  :data:`PARTICLE_SHARE`): the largest rank's owned plus halo particles over all particles;
- **per-step work that does not divide** (the hull's surface: pose, normals, facet grid; the
  coupling step's Python; histories: :data:`SERIAL_SHARE`): the same on every rank.

Speed-up S(P) = 1 / (sum of the parts' fractions); efficiency S / P. The refined sheets keep the
serial part's absolute cost (the hull mesh is the same), so their serial share falls with the
particle count. The seed paper's Table 5 (Zhang et al. 2023: 0.91-0.99 efficiency on 10-40
ranks) is an ice-dominated run; this is where pdfem's coupled step stands against it.
"""

from __future__ import annotations

import argparse
import json
import math

from pdfem.benchmarks.scaling_model import HORIZON_FACTOR, model_row

COUNTS = (105, 90, 3)
"""Lattice points per axis of the level-ice case's sheet (1.4 x 1.2 x 0.04 m at dx = 4/3 cm)."""

BOND_SHARE = 0.31
"""Share of one coupled step in the bond kernels (tiny case profile: 15.5 s of 49.7 s)."""

PARTICLE_SHARE = 0.48
"""Share in work proportional to the particles (hull contact detection 17.0 s, short-range
search 3.9 s, impulse work 2.2 s, water 0.5 s, of 49.7 s)."""

SERIAL_SHARE = 1.0 - BOND_SHARE - PARTICLE_SHARE
"""The rest: the rigid hull's surface and the coupling step's Python (per step, not divided)."""


def projection(refine: int, ranks: int) -> dict:
    """Speed-up and efficiency on ``ranks`` ranks of the sheet refined ``refine`` times."""
    counts = tuple(c * refine for c in COUNTS)
    n = math.prod(counts)
    one = model_row(counts, 1)
    row = model_row(counts, ranks)
    grow = n / math.prod(COUNTS)       # the ice's work per step grows with the particles
    bond = BOND_SHARE * grow * (row["compute_s"] + row["exchange_s"]) / one["compute_s"]
    particle = PARTICLE_SHARE * grow * (row["owned"] + row["halo"]) / n
    serial = SERIAL_SHARE
    whole = (BOND_SHARE + PARTICLE_SHARE) * grow + SERIAL_SHARE
    speedup = whole / (bond + particle + serial)
    return {"refine": refine, "particles": n, "ranks": ranks, "grid": row["grid"],
            "owned": row["owned"], "halo": row["halo"], "halo_fraction": row["halo_fraction"],
            "serial_share_one_rank": SERIAL_SHARE / whole, "speedup": speedup,
            "efficiency": speedup / ranks}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    rows = [projection(r, p) for r in (1, 2, 4) for p in (16, 32, 64)]
    if args.json:
        print(json.dumps({"horizon_factor": HORIZON_FACTOR, "rows": rows}, indent=1))
        return
    print("| sheet | particles | ranks | grid | owned | halo | halo / owned | serial share "
          "(1 rank) | speed-up | efficiency |")
    print("|---|---:|---:|---|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| dx / {r['refine']} | {r['particles']:,} | {r['ranks']} | {r['grid']} | "
              f"{r['owned']:,} | {r['halo']:,} | {r['halo_fraction']:.2f} | "
              f"{r['serial_share_one_rank']:.3f} | {r['speedup']:.1f} | {r['efficiency']:.2f} |")


if __name__ == "__main__":
    main()
