"""A partition of a lattice-filled body decided before any particle exists: a grid of boxes.

The distributed set-up (:mod:`pdfem.pd.layout.setup`) needs each rank's subdomain before
the particles are generated, so the cuts cannot be quantiles of particle coordinates
(:mod:`pdfem.parallel.partition`). Here they are lattice planes: along each axis the lattice
index range is cut into ``p_k`` runs holding equal numbers of particles according to the
marginal counts per lattice plane (exact for a box, whose planes all hold as many particles;
balanced by the counts of the planes for other shapes). A particle's owner is a function of its
lattice indices ``(i, j, k)`` alone, so every rank can tell the owner of any particle without
a global array. The grid shape (px, py, pz) is chosen to make the largest halo (the particles
within ``h`` lattice planes of a rank's box across its cut faces, estimated from the box's face
areas) smallest; ties go to the first shape in sorted order (deterministic). Lengths are in
lattice planes (multiply by the spacing dx for m).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pdfem.parallel.partition import grid_shapes


@dataclass(frozen=True)
class BoxPartition:
    """A px x py x pz grid of lattice-index boxes; rank = (a * py + b) * pz + c.

    Attributes
    ----------
    cuts
        Three int64 arrays of ``p_k + 1`` plane indices: box ``a`` along axis ``k`` holds the
        lattice planes ``cuts[k][a] : cuts[k][a + 1]``.
    """

    cuts: tuple[np.ndarray, np.ndarray, np.ndarray]

    @property
    def shape(self) -> tuple[int, int, int]:
        return tuple(len(c) - 1 for c in self.cuts)

    @property
    def name(self) -> str:
        return "boxes {}x{}x{}".format(*self.shape)

    @property
    def n_parts(self) -> int:
        px, py, pz = self.shape
        return px * py * pz

    def box(self, rank: int) -> tuple[np.ndarray, np.ndarray]:
        """The lattice index range ``[lo, hi)`` (two (3,) int64 arrays) of ``rank``'s box."""
        px, py, pz = self.shape
        a, rest = divmod(int(rank), py * pz)
        b, c = divmod(rest, pz)
        lo = np.array([self.cuts[0][a], self.cuts[1][b], self.cuts[2][c]], dtype=np.int64)
        hi = np.array([self.cuts[0][a + 1], self.cuts[1][b + 1], self.cuts[2][c + 1]],
                      dtype=np.int64)
        return lo, hi

    def owner(self, ijk: np.ndarray) -> np.ndarray:
        """Owner rank (int32, (M,)) of the lattice points with indices ``ijk`` (M, 3)."""
        ijk = np.asarray(ijk).reshape(-1, 3)
        _, py, pz = self.shape
        slot = [np.searchsorted(self.cuts[k][1:-1], ijk[:, k], side="right") for k in range(3)]
        return ((slot[0] * py + slot[1]) * pz + slot[2]).astype(np.int32)


def balanced_cuts(counts: np.ndarray, parts: int) -> np.ndarray:
    """``parts + 1`` plane indices cutting planes with ``counts`` particles into runs of about
    equal total (each cut at the plane where the running count first reaches its share; every
    run holds at least one plane when there are enough planes)."""
    counts = np.asarray(counts, dtype=np.float64)
    n = len(counts)
    cum = np.concatenate([[0.0], np.cumsum(counts)])
    targets = cum[-1] * np.arange(1, parts) / parts
    inner = np.searchsorted(cum, targets, side="left")
    cuts = np.concatenate([[0], inner, [n]]).astype(np.int64)
    for a in range(1, parts):  # keep the runs non-empty and ordered
        cuts[a] = min(max(cuts[a], cuts[a - 1] + 1), n - (parts - a))
    return cuts


def _largest_halo(cuts, h: int) -> float:
    """Largest estimated halo (lattice points) of the boxes of a cut: per rank, ``h`` planes
    across each face that has a neighbour, times that face's area."""
    worst = 0.0
    widths = [np.diff(c).astype(np.float64) for c in cuts]
    for a in range(len(widths[0])):
        for b in range(len(widths[1])):
            for c in range(len(widths[2])):
                w = (widths[0][a], widths[1][b], widths[2][c])
                faces = [(a > 0) + (a < len(widths[0]) - 1), (b > 0) + (b < len(widths[1]) - 1),
                         (c > 0) + (c < len(widths[2]) - 1)]
                halo = sum(faces[k] * h * w[(k + 1) % 3] * w[(k + 2) % 3] for k in range(3))
                worst = max(worst, halo)
    return worst


def choose_box_partition(plane_counts: list[np.ndarray], n_parts: int, h: int) -> BoxPartition:
    """The grid of lattice boxes for ``n_parts`` ranks with the smallest largest halo.

    Parameters
    ----------
    plane_counts
        Particles per lattice plane along x, y and z (marginal counts).
    n_parts
        Number of ranks.
    h
        Lattice planes a bond reaches across (``floor(delta / dx)``).

    Raises
    ------
    ValueError
        If no grid shape fits the lattice (more ranks than planes along every usable axis).
    """
    best = None
    for shape in grid_shapes(int(n_parts)):
        if any(shape[k] > len(plane_counts[k]) for k in range(3)):
            continue
        cuts = tuple(balanced_cuts(plane_counts[k], shape[k]) for k in range(3))
        key = _largest_halo(cuts, h)
        if best is None or key < best[0]:
            best = (key, cuts)
    if best is None:
        raise ValueError(f"the body's lattice is too small to be cut into {n_parts} boxes")
    return BoxPartition(best[1])
