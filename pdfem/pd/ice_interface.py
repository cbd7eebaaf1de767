"""The interface of an ice body that the coupler, the particle forces and the output use.

:class:`pdfem.pd.body.IceBody` implements it, for a body held whole by one process and for one
MPI rank's part of a body split over ranks alike (its :mod:`layout <pdfem.pd.layout.base>`
makes the difference). Code above it (contact, short-range forces, the driver and its output)
uses only what :class:`IceParticles` lists: per-particle arrays are the process's local ones,
``owned`` marks the particles it answers for, sums and gathers run over the owned particles of
all processes (collective under MPI).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class IceParticles(Protocol):
    """What the rest of pdfem needs from an ice body (SI units)."""

    name: str
    layout: object      # pdfem.pd.layout.base.Layout: exchanges, owned sums, gathers
    x0: np.ndarray      # (n, 3) reference positions of the local particles, m
    y: np.ndarray       # (n, 3) positions, m
    v: np.ndarray       # (n, 3) velocities, m/s
    f: np.ndarray       # (n, 3) force density, N/m^3 (particle forces add into it)
    vol: np.ndarray     # (n,) volumes, m^3
    gravity: np.ndarray  # (3,) uniform body acceleration of the kick, m/s^2

    @property
    def owned(self) -> np.ndarray:
        """(n,) bool: the local particles this process owns."""
        ...

    @property
    def n_global(self) -> int:
        """Particles of the whole body."""
        ...

    @property
    def layout_version(self) -> int:
        """Incremented when particles move between ranks (local indices change)."""
        ...

    def start(self) -> None: ...

    def begin_step(self, dt: float, keep_old: bool = False,
                   drift: bool = True) -> np.ndarray | None: ...

    def compute_forces(self) -> int: ...

    def refresh_forces(self) -> None:
        """After a force pass that broke bonds: the forces without them (recomputed until no
        further bond breaks at these positions, as a failure law whose bounds depend on the
        dilatation can break more once some are gone)."""
        ...

    def end_step(self, dt: float) -> None: ...

    @property
    def fracture_dissipated(self) -> float:
        """Energy (J) the bonds broken since the start held when they broke: at the positions
        y of their step, W(y; bonds before) - W(y; bonds after), summed over the steps
        (:mod:`pdfem.pd.failure.fracture`); over all ranks (collective), kept in checkpoints."""
        ...

    def owned_sum(self, values: np.ndarray):
        """Sum of a local per-particle array over the owned particles of all ranks."""
        ...

    def reactions(self) -> dict[str, np.ndarray]:
        """Reaction (N, (3,)) of each fixed or prescribed region by name: the force its support
        or driver exerts on the ice, over all ranks (collective)."""
        ...

    def gather(self, values: np.ndarray) -> np.ndarray | None:
        """Owned entries of a local per-particle array in global order on rank 0, else None."""
        ...

    def frame_fields(self) -> dict[str, np.ndarray] | None:
        """``{"u", "v", "damage"}`` in global order on rank 0 (None elsewhere; collective)."""
        ...

    def owned_reference(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Global numbers, reference positions (m) and volumes (m^3) of the owned particles."""
        ...

    def owned_frame_fields(self) -> dict[str, np.ndarray]:
        """:meth:`frame_fields` of the owned particles, in :meth:`owned_reference` order."""
        ...

    def imbalance(self) -> float:
        """Largest rank's work over the mean (1 for a whole body; collective)."""
        ...

    def rebalance(self, carry: dict[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
        """Re-partition over the ranks and move particles (nothing for a whole body); ``carry``
        holds other per-particle arrays ((n_local, k) float64, e.g. a particle force's state)
        that move with the particles: returned in the new local order."""
        ...
