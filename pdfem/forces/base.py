"""The particle-force interface: forces on ice particles other than their bonds.

A particle force acts on a list of ice bodies (:class:`pdfem.pd.ice_interface.IceParticles`).
Every ice step, once the bodies' bond forces are computed at the new positions, the coupler
(:class:`pdfem.coupling.coupler.Coupler`) calls :meth:`ParticleForce.add_forces` of each force
in its list, which adds force density (N/m^3) into the bodies' ``f`` arrays (for owned
particles; under MPI every call is collective). For the energy balance each force reports the
potential energy of its field (:meth:`ParticleForce.potential_energy`, J) under the history key
:attr:`ParticleForce.energy_key`; a force that dissipates energy (drag) also reports the energy it
has taken out so far (:meth:`ParticleForce.dissipated`) under :attr:`ParticleForce.dissipation_key`.

Adding a force
--------------
Write one new file in :mod:`pdfem.forces` with a subclass of :class:`ParticleForce`, and add
one line to the registry of particle-force kinds, :data:`pdfem.run.build_forces.PARTICLE_FORCES`
(its builder makes the force from the case, or returns ``None`` when the case does not use it).
"""

from __future__ import annotations

from abc import ABC, abstractmethod


class ParticleForce(ABC):
    """A force on ice particles, added to their force density every ice step (SI units)."""

    label: str = "particle force"
    """What the force is, for messages and the run's profile (:mod:`pdfem.run.profile`)."""

    energy_key: str = ""
    """Name of this force's potential energy in the energy history (J)."""

    dissipation_key: str = ""
    """Name of the energy this force dissipates in the energy history (J); "" for none."""

    @abstractmethod
    def add_forces(self) -> int | None:
        """Add this force's force density (N/m^3) at the current positions into the bodies'
        ``f``; may return a count for diagnostics (e.g. interacting pairs)."""

    @abstractmethod
    def potential_energy(self) -> float:
        """Potential energy (J) of the force at the current positions (0 for a force without
        one); the same on every rank."""

    def dissipated(self) -> float:
        """Energy (J) this force has taken out of the ice since the start (0 for a conservative
        force); the same on every rank."""
        return 0.0

    def checkpoint_state(self) -> dict:
        """Counters this force keeps between steps (energy taken out, positions at its last
        evaluation), for a checkpoint: per body ``k`` of its bodies, arrays ``<key>_<k>`` over
        this rank's owned particles with their global numbers ``gid_<k>`` (not collective;
        :mod:`pdfem.run.checkpoint_ranks`). Default: nothing (a force without memory)."""
        return {}

    def moving_state(self, body) -> dict:
        """The per-particle arrays this force keeps for ``body`` ((n_local, k) or (n_local,)
        float64, by name), handed to a re-partition that moves them with the particles
        (:meth:`pdfem.pd.ice_interface.IceParticles.rebalance`). Default: none."""
        return {}

    def moved_state(self, body, state: dict) -> None:
        """Take back :meth:`moving_state`'s arrays for ``body`` after a re-partition, in its
        new local particle order ((n_new, k) each). Default: nothing."""

    def restore_state(self, state: dict) -> None:
        """Put a state from :meth:`checkpoint_state` back, exactly: its ``<key>_<k>`` arrays
        come in body ``k``'s local particle order. Default: nothing."""
