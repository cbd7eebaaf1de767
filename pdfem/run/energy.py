"""The energy balance of a run: what the ice, the structures and the particle forces hold, what
was put in, and what was dissipated (J).

    stored   = ice kinetic + ice strain + gravity potential
               + structure kinetic + structure strain + short-range potential (+ further forces)
    supplied = initial stored + work of the ice's constraints + work of prescribed-motion
               structures (minus the work of the contact loads on them)
    dissipated = supplied - stored   (contact losses + fracture)

The sums are taken in this fixed order, so the history is the same bit for bit from run to run.
"""

from __future__ import annotations

from pdfem.run.build_forces import potential_energies

ICE_STORED = ("kinetic", "strain", "gravity_potential")
"""Stored-energy keys summed first (the ice and its body-force field), in order."""

SYSTEM_STORED = ("structure_kinetic", "structure_strain", "short_range_potential")
"""Stored-energy keys summed next (structures and interactions), in order."""


def _fold(e: dict, keys) -> float:
    """``e[k0] + e[k1] + ...`` summed left to right."""
    total = 0
    for k in keys:
        total = total + e[k]
    return total


def _further_potentials() -> tuple[str, ...]:
    """Potential-energy keys of particle-force kinds beyond gravity and short-range contact
    (:data:`pdfem.run.build_forces.PARTICLE_FORCES`), summed after the named terms."""
    return tuple(k for k in potential_energies([]) if k not in ICE_STORED + SYSTEM_STORED)


class EnergyBalance:
    """Energies of the bodies, structures and particle forces of a coupled run.

    Parameters
    ----------
    bodies, structures, forces, coupler
        Of the run (:class:`pdfem.coupling.coupler.Coupler` keeps the contact work).
    """

    def __init__(self, bodies: list, structures: list, forces: list, coupler) -> None:
        self.bodies, self.structures = bodies, structures
        self.forces, self.coupler = forces, coupler
        self.initial = 0.0

    def energies(self) -> dict[str, float]:
        """Every energy term (J) at the current state (collective under MPI)."""
        pot = potential_energies(self.forces)
        b, s, c = self.bodies, self.structures, self.coupler
        e = {"kinetic": sum(x.kinetic_energy() for x in b),
             "strain": sum(x.strain_energy() for x in b),
             "external_work": sum(x.external_work for x in b),
             "structure_kinetic": sum(x.kinetic_energy() for x in s),
             "structure_strain": sum(x.strain_energy() for x in s),
             "rigid_body_work": -sum(c.contact_work[id(x)] for x in s if x.prescribed_motion)}
        e.update(pot)
        return e

    def stored(self, e: dict) -> float:
        """Total stored energy (J) of the terms ``e``."""
        return _fold(e, ICE_STORED + SYSTEM_STORED + _further_potentials())

    def start(self) -> None:
        """Take the stored energy of the initial state as :attr:`initial`."""
        e = self.energies()
        self.initial = _fold(e, ICE_STORED) + _fold(e, SYSTEM_STORED + _further_potentials())

    def row(self) -> dict[str, float]:
        """The energy history row: every term, ``dissipated``, ``contact_dissipated`` and
        ``fracture_dissipated`` (J)."""
        e = self.energies()
        supplied = self.initial + e["external_work"] + e["rigid_body_work"]
        e["dissipated"] = supplied - self.stored(e)
        e["contact_dissipated"] = self.coupler.contact_dissipated
        e["fracture_dissipated"] = e["dissipated"] - e["contact_dissipated"]
        return e

    def supplied(self, e: dict) -> float:
        """Energy (J) supplied so far, from a :meth:`row`."""
        return self.initial + e["external_work"] + e["rigid_body_work"]
