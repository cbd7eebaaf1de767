"""The interface of an ice body that the coupler, the particle forces and the output use.

Two classes implement it: :class:`pdfem.pd.body.IceBody`, a whole body on one rank (through
:class:`WholeBody` below), and :class:`pdfem.pd.layout.halo.DistributedIce`, one rank's part of
a body split over MPI ranks. Code above them (contact, short-range forces, the driver and its
output) uses only what :class:`IceParticles` lists, so it never asks which of the two it holds:
per-particle arrays are the rank's local ones, ``owned`` marks the particles the rank answers
for, sums and gathers run over the owned particles of all ranks. A new kind of ice body
implements :class:`IceParticles` (one new file) and is made by a builder in :mod:`pdfem.run`.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class IceParticles(Protocol):
    """What the rest of pdfem needs from an ice body (SI units)."""

    name: str
    distributed: bool   # split over MPI ranks (every sum and gather is then collective)
    x0: np.ndarray      # (n, 3) reference positions of the local particles, m
    y: np.ndarray       # (n, 3) positions, m
    v: np.ndarray       # (n, 3) velocities, m/s
    f: np.ndarray       # (n, 3) force density, N/m^3 (particle forces add into it)
    vol: np.ndarray     # (n,) volumes, m^3
    gravity: np.ndarray  # (3,) uniform body acceleration of the kick, m/s^2
    layout_version: int  # incremented when particles move between ranks (local indices change)

    @property
    def owned(self) -> np.ndarray:
        """(n,) bool: the local particles this rank owns."""
        ...

    @property
    def global_body(self):
        """The whole body (:class:`pdfem.pd.body.IceBody`), as built on every rank."""
        ...

    def start(self) -> None: ...

    def begin_step(self, dt: float, keep_old: bool = False) -> np.ndarray | None: ...

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
        (:mod:`pdfem.pd.failure.fracture`); over all ranks (collective under MPI), kept in checkpoints."""
        ...

    def owned_sum(self, values: np.ndarray):
        """Sum of a local per-particle array over the owned particles of all ranks."""
        ...

    def reactions(self) -> dict[str, np.ndarray]:
        """Reaction (N, (3,)) of each fixed or prescribed region by name: the force its support
        or driver exerts on the ice, over all ranks (collective under MPI)."""
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
        """Largest rank's work over the mean (1 for a whole body; collective under MPI)."""
        ...

    def rebalance(self, carry: dict[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
        """Re-partition over the ranks and move particles (nothing for a whole body); ``carry``
        holds other per-particle arrays ((n_local, k) float64, e.g. a particle force's state)
        that move with the particles: returned in the new local order."""
        ...


class WholeBody:
    """:class:`IceParticles` for a body held whole by one rank: every particle is owned, sums
    are plain sums, gathers return the array itself. Needs ``n``, ``x0``, ``vol``, ``v``,
    ``displacement()`` and ``damage()`` of the class it is mixed into."""

    distributed = False
    layout_version = 0  # never changes: a whole body's particles stay on its rank

    def imbalance(self) -> float:
        """1: one rank holds the whole body."""
        return 1.0

    def rebalance(self, carry: dict[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
        """Nothing to move: one rank holds the whole body (``carry`` comes back as it is)."""
        return dict(carry or {})

    @property
    def owned(self) -> np.ndarray:
        """(N,) bool, all True."""
        return np.ones(self.n, dtype=np.bool_)

    @property
    def global_body(self):
        """The body itself."""
        return self

    def owned_sum(self, values: np.ndarray):
        """``values.sum(axis=0)``."""
        return values.sum(axis=0)

    def gather(self, values: np.ndarray) -> np.ndarray:
        """``values`` itself (already in global order)."""
        return values

    def frame_fields(self) -> dict[str, np.ndarray]:
        """``{"u" m, "v" m/s, "damage"}`` of every particle."""
        return {"u": self.displacement(), "v": self.v, "damage": self.damage()}

    def owned_reference(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``arange(n)``, ``x0`` (m), ``vol`` (m^3)."""
        return np.arange(self.n), self.x0, self.vol

    def owned_frame_fields(self) -> dict[str, np.ndarray]:
        """Same as :meth:`frame_fields`."""
        return self.frame_fields()
