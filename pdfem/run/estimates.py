"""Up-front estimates of a run's size, made from the case alone, before anything is built.

Particles: a box holds ``prod_k max(1, round(L_k / dx))`` lattice points exactly
(:mod:`pdfem.geometry.lattice`); a cylinder or a sphere about its volume / dx^3; a closed surface
mesh at most the lattice points of its bounding box. Pairs (bonds, i < j): the lattice offsets
``o != 0`` with ``|o| dx <= delta`` (the neighbour search's test) are counted once; half of them
(61 for ``delta = 3.015 dx``) is the number of pairs per interior particle. For a box the count
is exact: ``sum over half the offsets of prod_k max(0, n_k - |o_k|)``; otherwise it is the
interior figure times the particles (an upper bound: surface particles have fewer partners).

Memory: ``BYTES_PER_PARTICLE`` and ``BYTES_PER_PAIR`` come from measurements with a margin.
Per pair a body holds nbr (int32), xi_len (float64), the weight (float32, negative when the
bond is broken) and the pair loop's bond-length buffer (float64): 24 B. A 10-million-particle
body (597 million pairs) set up and stepped peaked at 16.4 GB, 24 B per pair and 213 B per
particle (benchmarks/memory_10m.py). A case whose estimate exceeds the memory available (``MemAvailable`` of
/proc/meminfo, else physical pages x page size) is refused before allocating anything.

Per rank (:func:`split_lattice`): the body's lattice box of ``n_k`` points per axis is cut into a
px x py x pz grid at the index bounds ``(j n_k) // p_k`` (the balanced cuts of
:func:`pdfem.parallel.partition.grid_partition` on a lattice). A rank's subdomain ``O`` owns
``prod_k len_k`` points; its halo are the points of the body outside ``O`` within the horizon of
a point of ``O``: a point whose distance to the box ``O`` in lattice units is ``e = (e_x, e_y,
e_z)`` (``e_k`` in 0..r, r = floor(delta/dx)) belongs to it when ``|e| <= delta/dx``, so the halo
is ``sum over such e of prod_k c_k(e_k) - owned`` with ``c_k(0) = len_k`` and ``c_k(e > 0)`` the
number of sides of ``O`` along k (0, 1 or 2) that have body points e planes away. Its bonds are
those with an owned end (how :mod:`pdfem.pd.layout.halo` keeps them): ``sum over i in O of
deg(i) - pairs(O)``, the degrees summed per offset of the whole family as a product of 1-D
interval overlaps. All exact for a box whose counts the grid divides (the run's partition cuts at
particle quantiles, so with an uneven division it may cut inside a lattice plane: a difference
of less than one plane per subdomain); other shapes are scaled by their fill fraction of the
lattice box.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from pdfem.parallel.partition import grid_shapes


BYTES_PER_PARTICLE = 240
"""Estimated resident bytes per ice particle (state, set-up and output arrays)."""

BYTES_PER_PAIR = 30
"""Estimated resident bytes per bond (pair arrays and the pair-loop workspace)."""

CRUSHED_ICE_BYTES_PER_PAIR = 4
"""Extra bytes per bond of a body whose crushed bonds push (``failure = "ice"``): the plastic
rest length (float32)."""

SHEAR_SPRING_BYTES_PER_PAIR = 12
"""Extra bytes per bond when crushed ice has friction: the shear spring's stretch (3 x float32,
:mod:`pdfem.pd.failure.crushed_shear`)."""

FIXED_BYTES = 200 * 2**20
"""Interpreter, libraries and compiled kernels (bytes), measured about 100-200 MB."""

MAX_PARTICLES = 10**13
"""Most ice particles of a case the estimates take (2.4 PB at ``BYTES_PER_PARTICLE``; the
largest run measured has 1e7): more is refused before an integer of the count is formed (so
counts and bytes stay exact in float64 and far inside int64)."""

MAX_PAIRS = 10**15
"""Most bonds of a case the estimates take (30 PB at ``BYTES_PER_PAIR``), for the same reason."""


@dataclass(frozen=True)
class BodyEstimate:
    """Estimated size of one ice body."""

    name: str
    particles: int
    pairs: int
    pairs_per_interior_particle: int
    exact: bool
    pair_bytes: int = BYTES_PER_PAIR

    @property
    def bytes(self) -> int:
        """Estimated memory of the body (bytes)."""
        return self.particles * BYTES_PER_PARTICLE + self.pairs * self.pair_bytes


def lattice_offsets(horizon_factor: float) -> np.ndarray:
    """(M, 3) int offsets ``o`` of half the family (first non-zero component positive) with
    ``|o| <= horizon_factor`` in lattice units: one per pair of an interior particle."""
    r = int(math.floor(horizon_factor))
    g = np.arange(-r, r + 1)
    o = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    inside = (o * o).sum(axis=1) <= horizon_factor * horizon_factor * (1 + 1e-12)
    first = np.where(o[:, 0] != 0, o[:, 0], np.where(o[:, 1] != 0, o[:, 1], o[:, 2]))
    return o[inside & (first > 0)]


def lattice_counts(shape, dx: float) -> tuple[int, int, int]:
    """Lattice points per axis of the bounding box of ``shape`` (m) at spacing ``dx`` (m)."""
    lo, hi = shape.bounds()
    return tuple(max(1, int(round((hi[k] - lo[k]) / dx))) for k in range(3))


def _axis_tables(n: int, p: int, r: int, family_k: np.ndarray):
    """Per-interval tables of one axis cut into ``p`` intervals of ``n`` points: lengths, the
    sides ``c(e)`` with points ``e = 1..r`` planes away, and for each family offset component
    ``v`` the points ``x`` of the interval with ``0 <= x + v < n``."""
    b = (np.arange(p + 1) * n) // p
    lo, hi = b[:-1], b[1:]
    side = np.empty((p, r + 1), dtype=np.float64)
    side[:, 0] = hi - lo
    for e in range(1, r + 1):
        side[:, e] = (lo - e >= 0).astype(np.float64) + (hi - 1 + e <= n - 1)
    overlap = np.maximum(0, np.minimum(hi[:, None], n - family_k[None, :])
                         - np.maximum(lo[:, None], -family_k[None, :])).astype(np.float64)
    return side, overlap


def split_lattice(counts, grid, horizon_factor: float) -> tuple[np.ndarray, np.ndarray,
                                                                  np.ndarray]:
    """Owned points, halo points and bonds with an owned end of every rank (arrays of length
    px py pz, rank = (i py + j) pz + k) of a lattice box of ``counts`` points per axis cut
    into ``grid`` = (px, py, pz), horizon ``horizon_factor`` dx (see the module docstring)."""
    half = lattice_offsets(horizon_factor)
    family = np.concatenate([half, -half])
    r = int(math.floor(horizon_factor))
    g = np.arange(r + 1)
    e = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    e = e[(e * e).sum(axis=1) <= horizon_factor * horizon_factor * (1 + 1e-12)]
    tabs = [_axis_tables(int(counts[k]), int(grid[k]), r, family[:, k]) for k in range(3)]
    (sx, ox), (sy, oy), (sz, oz) = tabs
    reach = np.einsum("ie,je,ke->ijk", sx[:, e[:, 0]], sy[:, e[:, 1]], sz[:, e[:, 2]])
    owned = np.einsum("i,j,k->ijk", sx[:, 0], sy[:, 0], sz[:, 0])
    degrees = np.einsum("io,jo,ko->ijk", ox, oy, oz)
    inner = np.einsum("io,jo,ko->ijk", *(np.maximum(0.0, s[:, :1] - np.abs(half[:, k])[None, :])
                                         for k, s in enumerate((sx, sy, sz))))
    return (owned.reshape(-1), (reach - owned).reshape(-1), (degrees - inner).reshape(-1))


def best_split(counts, horizon_factor: float, n_ranks: int):
    """``(grid, owned, halo, bonds)`` of the px x py x pz grid of ``n_ranks`` ranks over a
    lattice box of ``counts`` points whose largest rank needs least memory (bytes per particle
    and per bond as above; ties to the first grid of
    :func:`pdfem.parallel.partition.grid_shapes`), or ``None`` if no grid fits the counts."""
    best = None
    for grid in grid_shapes(n_ranks):
        if any(g > c for g, c in zip(grid, counts)):
            continue
        o, h, p = split_lattice(counts, grid, horizon_factor)
        worst = float(((o + h) * BYTES_PER_PARTICLE + p * BYTES_PER_PAIR).max())
        if best is None or worst < best[0]:
            best = (worst, grid, o, h, p)
    return None if best is None else best[1:]


def particle_count(shape, dx: float) -> tuple[float, bool]:
    """Particles of ``shape`` (m) at spacing ``dx`` (m) as a float (``inf`` when the count
    overflows) and whether it is exact: the lattice points of the bounding box, or for a shape
    that does not fill its box at most its volume / dx^3 (see the module docstring)."""
    lo, hi = shape.bounds()
    with np.errstate(over="ignore"):  # an absurd size: inf, refused by the preflight
        counts = np.maximum(1.0, np.rint((np.asarray(hi, dtype=np.float64)
                                          - np.asarray(lo, dtype=np.float64)) / dx))
        box = float(np.prod(counts))
    if shape.fills_bounds or box > MAX_PARTICLES or dx ** 3 == 0.0:
        return box, shape.fills_bounds
    return min(box, shape.volume_bound() / dx ** 3), False


def estimate_body(name: str, shape, dx: float, horizon: float,
                  pair_bytes: int = BYTES_PER_PAIR) -> BodyEstimate:
    """Particles and pairs of an ice body from its shape (m), spacing dx (m) and horizon (m),
    without building it (see the module docstring); ``pair_bytes`` per bond."""
    offsets = lattice_offsets(horizon / dx)
    n, exact = particle_count(shape, dx)
    if exact:
        counts = np.array(lattice_counts(shape, dx), dtype=np.float64)
        pairs = float(np.prod(np.maximum(0.0, counts[None, :] - np.abs(offsets)), axis=1).sum())
    else:
        pairs = n * len(offsets)
    return BodyEstimate(name, int(round(n)), int(round(pairs)), len(offsets), exact,
                        int(pair_bytes))


def available_memory() -> int | None:
    """Memory available to a new process (bytes): ``MemAvailable`` of /proc/meminfo, else the
    physical memory (``os.sysconf``); ``None`` if neither is known."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def format_bytes(n: float) -> str:
    """``n`` bytes as a short human-readable string (binary units)."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} PiB"
