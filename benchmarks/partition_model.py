"""The partition model: halo sizes, neighbours and traffic per step for N ranks, no cluster needed.

For the seed paper's 1,440,000-particle plate (Zhang et al. 2023, section 5; here a cubic
lattice of 600 x 300 x 8 particles, horizon 3.015 dx) and any rank count, every partitioner of
:mod:`pdfem.parallel.partition` is applied and its per-rank halo, communicating neighbours,
imbalance and bytes per step are counted exactly from the bond list. The seed observed that 8
ranks cut 4 x 2 ran faster than 10 ranks (their Fig. 12: the 10-rank split had more
communicating neighbours and unequal halos); :func:`partition_model` lets that be checked
for any shape and rank count.

Run it with ``python -m pdfem.benchmarks.partition_model [--ranks 2,4,8,10,16] [--json]``.
"""

from __future__ import annotations

import argparse
import json


from pdfem.geometry.lattice import fill
from pdfem.pd.bonds.search import cell_pairs
from pdfem.geometry.shapes import Box
from pdfem.parallel.partition import grid_partition, grid_shapes, partition_stats, rcb_partition

SEED_PLATE = (600, 300, 8)
"""Particles along x, y, z of the model plate: 1,440,000 particles, as in the seed's Table 3."""


def plate(shape=SEED_PLATE, dx: float = 1.0):
    """Lattice positions (cell order) and unique pairs of a plate of ``shape`` particles."""
    nx, ny, nz = shape
    x = fill(Box((0.0, 0.0, 0.0), (nx * dx, ny * dx, nz * dx)), dx)
    perm, row_ptr, nbr = cell_pairs(x, 3.015 * dx)
    return x[perm], row_ptr, nbr


def partition_model(ranks=(2, 4, 6, 8, 10, 12, 16, 24, 32, 48, 64), shape=SEED_PLATE) -> dict:
    """Partition statistics of the model plate for each rank count.

    Returns
    -------
    dict
        ``{"particles", "pairs", "plate": shape, "rows": [...]}``; each row is
        :meth:`~pdfem.parallel.partition.PartitionStats.summary` plus ``"best"`` (True for the
        partition :func:`~pdfem.parallel.partition.choose_partition` would pick): RCB and the
        best grid shape for every rank count.
    """
    x, row_ptr, nbr = plate(shape)
    rows = []
    for n in ranks:
        rcb = partition_stats(rcb_partition(x, n), row_ptr, nbr, n, "rcb")
        grids = [partition_stats(grid_partition(x, s), row_ptr, nbr, n, "grid {}x{}x{}".format(*s))
                 for s in grid_shapes(n) if s[2] == 1 or n <= 8]
        best_grid = min(grids, key=lambda st: (int(st.halo.max()), int(st.neighbours.max())))
        best = min((rcb, best_grid), key=lambda st: (int(st.halo.max()), int(st.neighbours.max())))
        for st in (rcb, best_grid):
            rows.append(dict(st.summary(), best=st is best))
    return {"particles": int(len(x)), "pairs": int(len(nbr)), "plate": list(shape), "rows": rows}


def markdown(result: dict) -> str:
    """The model as a Markdown table."""
    lines = [f"Plate {'x'.join(map(str, result['plate']))} particles ({result['particles']:,}; "
             f"{result['pairs']:,} unique pairs); halo = particles received per step; traffic "
             "= positions + dilatations of all halos, per step.", "",
             "| ranks | partition | max halo | mean halo | max neighbours | imbalance | "
             "traffic per step (MB) | chosen |",
             "|---:|---|---:|---:|---:|---:|---:|:---:|"]
    for r in result["rows"]:
        lines.append(f"| {r['ranks']} | {r['partition']} | {r['halo_max']:,} | "
                     f"{r['halo_mean']:,.0f} | {r['neighbours_max']} | {r['imbalance']:.1e} | "
                     f"{r['bytes_per_step'] / 1e6:.2f} | {'yes' if r['best'] else ''} |")
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ranks", default="2,4,6,8,10,12,16,24,32,48,64")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    result = partition_model(tuple(int(r) for r in args.ranks.split(",")))
    print(json.dumps(result) if args.json else markdown(result))


if __name__ == "__main__":
    main()
