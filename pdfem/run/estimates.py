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
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np


BYTES_PER_PARTICLE = 240
"""Estimated resident bytes per ice particle (state, set-up and output arrays)."""

BYTES_PER_PAIR = 30
"""Estimated resident bytes per bond (pair arrays and the pair-loop workspace)."""

FIXED_BYTES = 200 * 2**20
"""Interpreter, libraries and compiled kernels (bytes), measured about 100-200 MB."""


@dataclass(frozen=True)
class BodyEstimate:
    """Estimated size of one ice body."""

    name: str
    particles: int
    pairs: int
    pairs_per_interior_particle: int
    exact: bool

    @property
    def bytes(self) -> int:
        """Estimated memory of the body (bytes)."""
        return self.particles * BYTES_PER_PARTICLE + self.pairs * BYTES_PER_PAIR


def lattice_offsets(horizon_factor: float) -> np.ndarray:
    """(M, 3) int offsets ``o`` of half the family (first non-zero component positive) with
    ``|o| <= horizon_factor`` in lattice units: one per pair of an interior particle."""
    r = int(math.floor(horizon_factor))
    g = np.arange(-r, r + 1)
    o = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    inside = (o * o).sum(axis=1) <= horizon_factor * horizon_factor * (1 + 1e-12)
    first = np.where(o[:, 0] != 0, o[:, 0], np.where(o[:, 1] != 0, o[:, 1], o[:, 2]))
    return o[inside & (first > 0)]


def _particles(shape, dx: float) -> tuple[float, bool]:
    lo, hi = shape.bounds()
    counts = [max(1, int(round((hi[k] - lo[k]) / dx))) for k in range(3)]
    box = float(np.prod(np.asarray(counts, dtype=np.float64)))
    if shape.fills_bounds:
        return box, True
    return min(box, shape.volume_bound() / dx ** 3), False


def estimate_body(name: str, shape, dx: float, horizon: float) -> BodyEstimate:
    """Particles and pairs of an ice body from its shape (m), spacing dx (m) and horizon (m),
    without building it (see the module docstring)."""
    offsets = lattice_offsets(horizon / dx)
    n, exact = _particles(shape, dx)
    if exact:
        lo, hi = shape.bounds()
        counts = np.array([max(1, int(round((hi[k] - lo[k]) / dx))) for k in range(3)],
                          dtype=np.float64)
        pairs = float(np.prod(np.maximum(0.0, counts[None, :] - np.abs(offsets)), axis=1).sum())
    else:
        pairs = n * len(offsets)
    return BodyEstimate(name, int(round(n)), int(round(pairs)), len(offsets), exact)


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
