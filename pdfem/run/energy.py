"""The energy balance of a run, every term computed on its own, and its residual (J).

    stored     = ice kinetic + ice kinetic correction + ice strain + gravity potential
                 + short-range potential
                 (+ further particle-force potentials)
                 + structure kinetic + structure kinetic correction + structure strain
                 + structure potential (a floating ship's gravity and hydrostatics)
    supplied   = initial stored + work of the ice's constraints (``external_work``)
                 + work of prescribed structure motions (``rigid_body_work``)
                 + work of the structures' applied loads (``load_work``)
                 + work of moving supports (``support_work``)
    dissipated = contact (plastic impulses and friction) + fracture (energy the broken bonds
                 held) + structural damping (+ particle forces' dissipation, e.g. water drag)
    residual   = supplied - stored - dissipated

Each term is kept by its owner as the run goes: the coupler keeps the work of the contact
impulses (:attr:`pdfem.coupling.coupler.Coupler.contact_dissipated`), each ice body the energy
its broken bonds released (``fracture_dissipated``) and the work of its constraints, each
structure the work of its loads and supports and its damping loss
(:meth:`pdfem.fem.base.Structure.energy_terms`). Nothing is "whatever is left over", so the
residual measures what the scheme gets wrong: the time-integration error of the ice
(velocity Verlet, O(dt^2)) and of the coupling. ``structure_kinetic_correction`` is the
central-difference scheme's own share of the kinetic energy (``-(dt^2/8) a . M a``,
:meth:`pdfem.fem.explicit.CentralDifference.kinetic_correction`): with it the structure's
balance is exact, without it a structure ringing in its highest modes would show up to a
third of their energy as residual. ``kinetic_correction`` is the same share of the ice's
velocity Verlet (``-(h^2/8) sum rho V |a|^2`` at the ice step h,
:func:`pdfem.pd.diagnostics.kinetic_correction`): without it the first contact of a coarse
impact showed 1-6 % of the energy supplied as "created" while the ice rang (an elastic cube's
impact: 1.76 %, with it 0.000 %; a sphere pressed into a block: 5.6 %, with it 0.000 %).

The sums are taken in this fixed order, so the history is the same bit for bit from run to run.
"""

from __future__ import annotations

from pdfem.run.build_forces import dissipated_energies, potential_energies

ICE_STORED = ("kinetic", "kinetic_correction", "strain", "gravity_potential")
"""Stored-energy keys summed first (the ice and its body-force field), in order."""

SYSTEM_STORED = ("structure_kinetic", "structure_kinetic_correction", "structure_strain",
                 "structure_potential", "short_range_potential")
"""Stored-energy keys summed next (structures and interactions), in order."""

SUPPLIED = ("external_work", "rigid_body_work", "load_work", "support_work")
"""Work put in, added to the initial stored energy, in order."""

DISSIPATED = ("contact_dissipated", "fracture_dissipated", "damping_dissipated")
"""Energy lost, in order."""


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
    ice_step
        The ice's velocity-Verlet step h (s), for its kinetic correction.
    """

    def __init__(self, bodies: list, structures: list, forces: list, coupler,
                 ice_step: float) -> None:
        self.bodies, self.structures = bodies, structures
        self.forces, self.coupler = forces, coupler
        self.ice_step = float(ice_step)
        self.initial = 0.0

    def energies(self) -> dict[str, float]:
        """Every energy term (J) at the current state (collective under MPI)."""
        pot = potential_energies(self.forces)
        b, s, c = self.bodies, self.structures, self.coupler
        terms = [x.energy_terms() for x in s]
        e = {"kinetic": sum(x.kinetic_energy() for x in b),
             "kinetic_correction": sum(x.kinetic_correction(self.ice_step) for x in b),
             "strain": sum(x.strain_energy(forces_current=True) for x in b),
             "external_work": sum(x.external_work for x in b),
             "fracture_dissipated": sum(x.fracture_dissipated for x in b),
             "structure_kinetic": sum(x.kinetic_energy() for x in s),
             "structure_kinetic_correction": sum(t["kinetic_correction"] for t in terms),
             "structure_strain": sum(x.strain_energy() for x in s),
             "structure_potential": sum(x.potential_energy() for x in s),
             "rigid_body_work": -sum(r.contact_work for r in c.records
                                     if r.structure.prescribed_motion),
             "load_work": sum(t["load_work"] for t in terms),
             "support_work": sum(t["support_work"] for t in terms),
             "damping_dissipated": sum(t["damping_dissipated"] for t in terms),
             "contact_dissipated": c.contact_dissipated}
        e.update(pot)
        e.update(dissipated_energies(self.forces))
        return e

    def stored(self, e: dict) -> float:
        """Total stored energy (J) of the terms ``e``."""
        return _fold(e, ICE_STORED + SYSTEM_STORED + _further_potentials())

    def start(self) -> None:
        """Take the stored energy of the initial state as :attr:`initial`."""
        e = self.energies()
        self.initial = _fold(e, ICE_STORED) + _fold(e, SYSTEM_STORED + _further_potentials())

    def row(self) -> dict[str, float]:
        """The energy history row: every term, ``supplied``, ``stored``, ``dissipated`` (the sum
        of the dissipation terms) and ``residual`` (J)."""
        e = self.energies()
        e["supplied"] = self.supplied(e)
        e["stored"] = self.stored(e)
        e["dissipated"] = _fold(e, DISSIPATED + tuple(dissipated_energies([])))
        e["residual"] = e["supplied"] - e["stored"] - e["dissipated"]
        return e

    def supplied(self, e: dict) -> float:
        """Energy (J) supplied so far: the initial stored energy plus the work put in."""
        return self.initial + _fold(e, SUPPLIED)


BUDGET_LINES = (("work in (initial energy + work done on the system)", ("supplied",)),
                ("ice kinetic", ("kinetic", "kinetic_correction")),
                ("ice strain", ("strain",)),
                ("structure kinetic", ("structure_kinetic", "structure_kinetic_correction")),
                ("structure strain", ("structure_strain",)),
                ("potentials (gravity, ship afloat, short-range, ...)", None),
                ("dissipated by contact (plastic impulses, friction)", ("contact_dissipated",)),
                ("dissipated by fracture", ("fracture_dissipated",)),
                ("dissipated by damping", ("damping_dissipated",)),
                ("residual (supplied - stored - dissipated)", ("residual",)))
"""The lines of the energy budget: label and the energy-row keys summed (``None``: every
potential-energy term)."""


def budget(row: dict[str, float]) -> list[tuple[str, float, float]]:
    """The energy budget of an energy row (:meth:`EnergyBalance.row`): ``(label, J, % of the
    energy supplied)`` per line of :data:`BUDGET_LINES`; the lines after the first sum to the
    first (the residual closes it)."""
    potentials = (("gravity_potential", "structure_potential", "short_range_potential")
                  + _further_potentials())
    supplied = row["supplied"]
    out = []
    for label, keys in BUDGET_LINES:
        value = _fold(row, tuple(k for k in (keys or potentials) if k in row))
        out.append((label, float(value), 100.0 * value / supplied if supplied else 0.0))
    return out


def budget_text(row: dict[str, float]) -> str:
    """The energy budget as aligned lines (J and % of the energy supplied)."""
    return "\n".join(f"    {label:<52s} {value:12.5g} J {pct:8.3f} %"
                     for label, value, pct in budget(row))
