"""Before anything is built: the particles, bonds and memory a case needs per rank and per node,
refused (exit 2) if a node cannot hold its ranks.

Each ice body is split over the ranks as a grid of its lattice box (the grid shape whose largest
rank needs least; :func:`pdfem.run.estimates.split_lattice`: owned and halo particles, bonds with
an owned end). A rank's memory is ``FIXED_BYTES`` plus, per body, its local particles x
``BYTES_PER_PARTICLE`` + its bonds x ``BYTES_PER_PAIR`` (bytes). Two set-ups:

* distributed (:mod:`pdfem.pd.layout.setup`: each rank builds only its subdomain and
  halo): that is the rank's peak;
* global (every rank first builds the whole body, then keeps its part, so the peak per rank is
  the whole body plus its part): no run uses it any more; ``pdfem run --estimate --setup
  global`` sizes it for comparison.

Runs use the distributed set-up. A node's need is the sum
over its ranks (ranks sharing memory: :func:`pdfem.parallel.nodes.node_layout`), compared with its
``MemAvailable``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pdfem.case.schema import Case
from pdfem.errors import InputError
from pdfem.parallel.nodes import block_layout, node_layout, per_node
from pdfem.run.estimates import (BYTES_PER_PAIR, BYTES_PER_PARTICLE, CRUSHED_ICE_BYTES_PER_PAIR,
                                 FIXED_BYTES, MAX_PAIRS, MAX_PARTICLES,
                                 SHEAR_SPRING_BYTES_PER_PAIR, BodyEstimate, available_memory,
                                 best_split, estimate_body, format_bytes, lattice_counts,
                                 lattice_offsets, particle_count)

SETUP_TEXT = {True: "distributed set-up: each rank builds only its subdomain and halo",
              False: "global set-up: every rank builds the whole ice body, then keeps its part, "
                     "so a rank's peak is the whole body plus its part"}
"""How each set-up is named in reports."""


@dataclass(frozen=True)
class RankEstimate:
    """One rank's share of the ice, summed over the bodies, and its peak memory (bytes)."""

    rank: int
    owned: int
    halo: int
    bonds: int
    bytes: int


def check_size(case: Case) -> None:
    """Refuse ice of more than :data:`~pdfem.run.estimates.MAX_PARTICLES` particles or
    :data:`~pdfem.run.estimates.MAX_PAIRS` bonds in all (counted as floats: a spacing or a shape
    that overflows them is refused, not estimated).

    Raises
    ------
    InputError
        Naming the ``dx`` of the body with the most particles, its shape and the bounds.
    """
    counts = [particle_count(c.shape, c.dx)[0] for c in case.ice]
    pairs = [n * len(lattice_offsets(c.horizon / c.dx)) for n, c in zip(counts, case.ice)]
    if sum(counts) <= MAX_PARTICLES and sum(pairs) <= MAX_PAIRS:
        return
    k = max(range(len(counts)), key=lambda j: (counts[j], pairs[j]))
    cfg = case.ice[k]
    lo, hi = cfg.shape.bounds()
    span = " x ".join(f"{hi[j] - lo[j]:.3g}" for j in range(3))
    raise InputError(case.file, f"{cfg.field}.dx",
                     f"ice body '{cfg.name}' would have about {counts[k]:.3g} particles and "
                     f"{pairs[k]:.3g} bonds (its shape, {cfg.field}.shape, spans {span} m); the "
                     f"estimates take at most {MAX_PARTICLES:.0e} particles and {MAX_PAIRS:.0e} "
                     f"bonds in a case ({format_bytes(MAX_PARTICLES * BYTES_PER_PARTICLE)} of "
                     "memory; the largest run measured has 1e7 particles): choose a larger dx (m) "
                     "or a smaller shape", cfg.dx)


def estimate_case(case: Case) -> list[BodyEstimate]:
    """Particles, pairs and memory of every ice body of a case, before building
    (:func:`pdfem.run.estimates.estimate_body`), after :func:`check_size`."""
    check_size(case)
    return [estimate_body(c.name, c.shape, c.dx, c.horizon, pair_bytes(c.material))
            for c in case.ice]


def pair_bytes(material) -> int:
    """Bytes per bond of an ice body with this case material (crushed ice holds more)."""
    if material.failure != "ice":
        return BYTES_PER_PAIR
    return BYTES_PER_PAIR + CRUSHED_ICE_BYTES_PER_PAIR + (
        SHEAR_SPRING_BYTES_PER_PAIR if material.crushed_friction > 0.0 else 0)


def split_body(cfg, est: BodyEstimate, n_ranks: int, file: str | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Owned, halo and bond counts per rank of one ice body (``cfg`` its case entry) on
    ``n_ranks`` ranks: the grid of its lattice box whose largest rank needs least memory
    (:func:`pdfem.run.estimates.best_split`), scaled by the body's fill fraction of the box
    when it is not a box."""
    counts = lattice_counts(cfg.shape, cfg.dx)
    split = best_split(counts, cfg.horizon / cfg.dx, n_ranks)
    if split is None:
        raise InputError(file, f"{cfg.field}.dx", f"ice body '{cfg.name}' has too few lattice "
                         f"points per axis {counts} to be shared by {n_ranks} ranks (each needs "
                         "at least one plane); use fewer ranks or a smaller dx", cfg.dx)
    fill = est.particles / float(np.prod(counts))
    return tuple(np.rint(a * fill).astype(np.int64) for a in split[1:])


def estimate_rank_memory(case: Case, n_ranks: int, distributed_setup: bool
                         ) -> list[RankEstimate]:
    """The ice particles, bonds and peak memory (bytes) of every rank of ``case`` on
    ``n_ranks`` ranks, for the distributed or today's global set-up (module docstring)."""
    bodies = estimate_case(case)
    owned = np.zeros(n_ranks, np.int64)
    halo, bonds, local = owned.copy(), owned.copy(), owned.copy()
    for cfg, est in zip(case.ice, bodies):
        o, h, p = split_body(cfg, est, n_ranks, case.file) if n_ranks > 1 else (
            np.array([est.particles]), np.zeros(1, np.int64), np.array([est.pairs]))
        owned += o
        halo += h
        bonds += p
        local += (o + h) * BYTES_PER_PARTICLE + p * est.pair_bytes
    whole = sum(e.bytes for e in bodies) if (n_ranks > 1 and not distributed_setup) else 0
    return [RankEstimate(r, int(owned[r]), int(halo[r]), int(bonds[r]),
                         int(FIXED_BYTES + whole + local[r])) for r in range(n_ranks)]


def node_needs(ranks: list[RankEstimate], nodes: list[int]) -> list[int]:
    """Bytes each node needs: the sum over its ranks."""
    return [int(v) for v in np.bincount(nodes, weights=[r.bytes for r in ranks])]


def nodes_needed(ranks: list[RankEstimate], node_bytes: int) -> tuple[int, int] | None:
    """(nodes, ranks per node) of the fewest nodes of ``node_bytes`` that hold these ranks in
    SLURM's block layout; ``None`` if even one rank per node does not fit."""
    n = len(ranks)
    for per in range(n, 0, -1):
        layout = block_layout(n, math.ceil(n / per))
        if max(node_needs(ranks, layout)) <= node_bytes:
            return max(layout) + 1, per
    return None


def check_nodes(case: Case, ranks: list[RankEstimate], nodes: list[int],
                available: list[int | None], distributed_setup: bool) -> None:
    """Refuse a run one of whose nodes cannot hold its ranks.

    Raises
    ------
    InputError
        One paragraph: the case file, the estimate per rank and per node, what is available and
        how many nodes of that size the run needs at this rank count.
    """
    need = node_needs(ranks, nodes)
    over = [k for k, a in enumerate(available) if a is not None and need[k] > a]
    if not over or not case.ice:
        return
    k = max(over, key=lambda j: need[j] - available[j])
    big = max(ranks, key=lambda r: r.bytes)
    mine = [r for r, n in enumerate(nodes) if n == k]
    fit = nodes_needed(ranks, min(a for a in available if a is not None))
    bodies = estimate_case(case)
    total = sum(e.particles for e in bodies), sum(e.pairs for e in bodies)
    text = (f"the run needs about {format_bytes(need[k])} of memory on node {k} (its "
            f"{len(mine)} rank{'s' if len(mine) > 1 else ''}) but "
            f"{format_bytes(available[k])} is available there; the ice has about "
            f"{total[0]:,} particles and {total[1]:,} bonds ({SETUP_TEXT[distributed_setup]}); "
            f"the largest rank (rank {big.rank}: "
            f"{big.owned:,} owned + {big.halo:,} halo particles, {big.bonds:,} bonds) needs "
            f"about {format_bytes(big.bytes)}. ")
    if fit is not None:
        text += (f"At {len(ranks)} ranks it needs {fit[0]} node{'s' if fit[0] > 1 else ''} of "
                 f"this size ({fit[1]} rank{'s' if fit[1] > 1 else ''} per node); size the "
                 "job with pdfem run CASE "
                 "--estimate --ranks N --nodes K, choose a larger dx, or a smaller body")
    elif distributed_setup:
        text += ("Even one rank per node does not fit: use more ranks (each holds about "
                 "1/N of the ice), a larger dx, or a smaller body")
    else:
        text += ("Even one rank per node does not fit, and more ranks do not help while every "
                 "rank builds the whole body: choose a larger dx, a smaller body, or nodes with "
                 "more memory")
    big_body = max(range(len(bodies)), key=lambda b: bodies[b].bytes)
    raise InputError(case.file, f"{case.ice[big_body].field}.dx", text, case.ice[big_body].dx)


def rank_table(ranks: list[RankEstimate], nodes: list[int], rows: int = 16) -> list[str]:
    """Report lines: rank, node, particles owned + halo, bonds, memory (the first ``rows``
    ranks and the largest)."""
    big = max(ranks, key=lambda r: r.bytes).rank
    out = ["  rank  node        owned +       halo          bonds     memory"]
    for r in ranks:
        if r.rank < rows or r.rank == big:
            out.append(f"  {r.rank:4d}  {nodes[r.rank]:4d}  {r.owned:13,} + {r.halo:10,}  "
                       f"{r.bonds:13,}  {format_bytes(r.bytes):>9}"
                       + ("  (largest)" if r.rank == big and len(ranks) > 1 else ""))
        elif r.rank == rows:
            out.append(f"  ... ({len(ranks) - rows} more ranks)")
    return out


def node_lines(ranks: list[RankEstimate], nodes: list[int], available: list[int | None],
               rows: int = 16) -> list[str]:
    """Report lines: each node's ranks, need and available memory (the first ``rows``)."""
    need = node_needs(ranks, nodes)
    out = []
    for k, (n, a) in enumerate(zip(need, available)):
        if k < rows:
            count = nodes.count(k)
            out.append(f"  node {k}: {count} rank{'s' if count > 1 else ''}, needs "
                       f"{format_bytes(n)} of {format_bytes(a) if a else 'unknown'} available")
    if len(need) > rows:
        out.append(f"  ... ({len(need) - rows} more nodes, the largest need "
                   f"{format_bytes(max(need))})")
    return out


def body_lines(case: Case) -> list[str]:
    """Report lines: particles, bonds and memory of each whole ice body."""
    return [f"  estimate for ice '{e.name}': {e.particles:,} particles, {e.pairs:,} bonds "
            f"({e.pairs_per_interior_particle} per interior particle"
            f"{'' if e.exact else ', an upper bound'}), {format_bytes(e.bytes)}"
            for e in estimate_case(case)]


def preflight(case: Case, comm) -> list[str]:
    """Estimate the ice of ``case`` per rank of ``comm`` and per node, and refuse a run that
    cannot fit (collective under MPI); the report lines (the same on every rank).

    Raises
    ------
    InputError
        From :func:`check_nodes`.
    """
    setup = True  # runs build their ice split over the ranks (pdfem.pd.layout.setup)
    ranks = estimate_rank_memory(case, comm.size, setup)
    nodes = node_layout(comm)
    available = per_node(comm, nodes, available_memory)
    check_nodes(case, ranks, nodes, available, setup)
    lines = body_lines(case)
    if not case.ice:
        return lines
    if comm.size > 1:
        lines.append(f"  memory per rank, {SETUP_TEXT[setup]}:")
        lines += rank_table(ranks, nodes) + node_lines(ranks, nodes, available)
    else:
        lines.append(f"  estimated memory {format_bytes(ranks[0].bytes)} of "
                     f"{format_bytes(available[0]) if available[0] else 'unknown'} available")
    return lines
