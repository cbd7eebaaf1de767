"""The scaling model: halo, traffic, memory and time per step per rank at 10^8-10^9 particles.

For an ice body of N particles on P ranks (P = 64 ... 1024) it takes the exact lattice counts of
:func:`pdfem.run.estimates.best_split` (the grid of the lattice box whose largest rank needs
least memory: owned and halo particles, bonds with an owned end) and derives, for the largest
rank:

- the halo fraction (halo / owned); for a cube of n owned particles it is close to
  ``6 r / n^(1/3)`` (r = 3 lattice planes of horizon on each cut face), for a column through a
  sheet of thickness h and side a close to ``4 r / a``;
- bytes received per step: halo x 32 B (positions, then dilatations: 4 float64,
  :data:`pdfem.parallel.partition.BYTES_PER_HALO_PARTICLE`);
- memory per rank: 200 MiB + 240 B per local particle + 30 B per bond
  (:mod:`pdfem.run.estimates`), for the distributed set-up, and today's global set-up (the whole
  body on every rank);
- time per step: bonds / RATE (one core) plus two exchanges of LATENCY per neighbour and the
  bytes over BANDWIDTH; and, as a pessimistic bound, the exchange at the cost per halo particle
  measured on 2 ranks here (MEASURED_EXCHANGE_PER_HALO).

Two bodies: a cube, and a level-ice sheet 20 particles thick (1 m at dx = 5 cm). Run it with
``python -m pdfem.benchmarks.scaling_model [--json]`` (a few seconds; no MPI needed).
"""

from __future__ import annotations

import argparse
import json
import math

from pdfem.parallel.partition import BYTES_PER_HALO_PARTICLE
from pdfem.run.estimates import (BYTES_PER_PAIR, BYTES_PER_PARTICLE, FIXED_BYTES, best_split,
                                 split_lattice)

RATE = 125.4e6
"""Bond-steps per second of one rank on one core (BENCHMARKS.md, MPI strong scaling, 1 rank)."""

LATENCY = 2e-6
"""Seconds per message (an InfiniBand-class network; assumed)."""

BANDWIDTH = 10e9
"""Bytes per second a rank receives (100 Gb/s network; assumed)."""

HORIZON_FACTOR = 3.015
"""Horizon over dx, as in every pdfem case by default."""

MEASURED_EXCHANGE_PER_HALO = 0.0086 / 15000
"""Seconds per halo particle and step of the two exchanges measured on 2 ranks of this 2-core
machine (BENCHMARKS.md, MPI strong scaling: 8.6 ms for 15,000 halo particles); mostly waiting
for the other rank, so a pessimistic bound on a network."""

SHEET_LAYERS = 20
"""Particles through the sheet's thickness."""


def bodies(n: float) -> dict[str, tuple[int, int, int]]:
    """Lattice counts of a cube and of a square sheet of about ``n`` particles."""
    side = round(n ** (1 / 3))
    a = round(math.sqrt(n / SHEET_LAYERS))
    return {"cube": (side, side, side), "sheet": (a, a, SHEET_LAYERS)}


def model_row(counts, ranks: int) -> dict:
    """The largest rank's figures for a lattice box of ``counts`` points on ``ranks`` ranks."""
    grid, owned, halo, bonds = best_split(counts, HORIZON_FACTOR, ranks)
    r = int(((owned + halo) * BYTES_PER_PARTICLE + bonds * BYTES_PER_PAIR).argmax())
    n = math.prod(counts)
    all_bonds = float(split_lattice(counts, (1, 1, 1), HORIZON_FACTOR)[2][0])
    whole = n * BYTES_PER_PARTICLE + all_bonds * BYTES_PER_PAIR  # today: on every rank
    local = int((owned[r] + halo[r]) * BYTES_PER_PARTICLE + bonds[r] * BYTES_PER_PAIR)
    neighbours = math.prod(min(p, 3) for p in grid) - 1
    received = int(halo[r]) * BYTES_PER_HALO_PARTICLE
    compute = float(bonds[r]) / RATE
    exchange = 2 * neighbours * LATENCY + received / BANDWIDTH
    return {"particles": n, "bonds": int(all_bonds), "ranks": ranks,
            "grid": "x".join(map(str, grid)),
            "owned": int(owned[r]), "halo": int(halo[r]),
            "halo_fraction": float(halo[r] / owned[r]), "neighbours": neighbours,
            "bytes_per_step": received, "total_bytes_per_step": int(halo.sum())
            * BYTES_PER_HALO_PARTICLE, "memory": FIXED_BYTES + local,
            "memory_global_setup": FIXED_BYTES + local + whole,
            "compute_s": compute, "exchange_s": exchange,
            "exchange_share": exchange / (compute + exchange),
            "measured_exchange_share": (halo[r] * MEASURED_EXCHANGE_PER_HALO)
            / (compute + halo[r] * MEASURED_EXCHANGE_PER_HALO)}


def scaling_model(sizes=(1e8, 1e9), ranks=(64, 128, 256, 512, 1024)) -> list[dict]:
    """Rows of :func:`model_row` for each body shape, size and rank count."""
    rows = []
    for n in sizes:
        for name, counts in bodies(n).items():
            for p in ranks:
                rows.append(dict(model_row(counts, p), body=name, counts=list(counts)))
    return rows


def markdown(rows: list[dict]) -> str:
    """The rows as a Markdown table."""
    out = ["| body | particles | ranks | grid | owned | halo | halo / owned | received per "
           "step (MB) | memory per rank (GiB) | today, global set-up (GiB) | step (s) | "
           "exchange share | exchange share at the 2-rank cost |",
           "|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        out.append(f"| {r['body']} {'x'.join(map(str, r['counts']))} | {r['particles']:.2e} | "
                   f"{r['ranks']} | {r['grid']} | {r['owned']:,} | {r['halo']:,} | "
                   f"{r['halo_fraction']:.3f} | {r['bytes_per_step'] / 1e6:.1f} | "
                   f"{r['memory'] / 2**30:.2f} | {r['memory_global_setup'] / 2**30:,.0f} | "
                   f"{r['compute_s'] + r['exchange_s']:.3f} | {r['exchange_share']:.1%} | "
                   f"{r['measured_exchange_share']:.0%} |")
    return "\n".join(out)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    rows = scaling_model()
    print(json.dumps(rows) if args.json else markdown(rows))


if __name__ == "__main__":
    main()
