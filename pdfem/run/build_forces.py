"""Particle forces of a run from the case: the registry of particle-force kinds.

:data:`PARTICLE_FORCES` maps each kind (a :class:`pdfem.forces.base.ParticleForce` subclass) to
its builder ``(case, bodies) -> force or None`` (None: the case does not use it). A new kind is
one new file in :mod:`pdfem.forces` and one entry here. Every registered kind has a column
(:attr:`~pdfem.forces.base.ParticleForce.energy_key`) in the energy history, 0 when unused, so
runs with and without it write the same columns.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

from pdfem.case.schema import Case
from pdfem.errors import InputError
from pdfem.forces.base import ParticleForce
from pdfem.forces.gravity import Gravity
from pdfem.forces.short_range import ShortRangeContact
from pdfem.forces.water import Water


def _gravity(case: Case, bodies: list) -> Gravity:
    return Gravity(bodies, case.run.gravity)


def _short_range(case: Case, bodies: list) -> ShortRangeContact | None:
    # crushed ice (a law whose broken bonds push) meets unbonded ice only through this force
    crushing = any(b.failure.broken_bonds_push for b in bodies)
    on = case.run.short_range_contact or crushing
    return ShortRangeContact(bodies) if on and bodies else None


def _water(case: Case, bodies: list) -> Water | None:
    w = case.water
    if w is None or not bodies:
        return None
    gx, gy, gz = case.run.gravity
    if gx != 0.0 or gy != 0.0 or gz >= 0.0:
        raise InputError(case.file, "run.gravity", "with [water] gravity must point down z "
                         "(the water surface is the plane z = water.level): give [0, 0, -g] "
                         "with g > 0, or leave run.gravity out for [0, 0, -9.81]",
                         list(case.run.gravity))
    water = Water(bodies, density=w.density, level=w.level, g=-gz, current=w.current,
                  linear_drag=w.linear_drag, drag_coefficient=w.drag_coefficient,
                  added_mass=w.added_mass)
    for message in water.out_of_equilibrium():
        warnings.warn(f"{case.file}: {message}", stacklevel=2)
    return water


PARTICLE_FORCES: dict[type[ParticleForce], Callable[[Case, list], ParticleForce | None]] = {
    Gravity: _gravity,
    ShortRangeContact: _short_range,
    Water: _water,  # last: its added mass rescales the forces added before it
}
"""Particle-force kind -> builder; forces act in this order every ice step."""


def build_forces(case: Case, bodies: list) -> list[ParticleForce]:
    """The particle forces the case uses on its ice bodies (after they are distributed)."""
    forces = (build(case, bodies) for build in PARTICLE_FORCES.values())
    return [f for f in forces if f is not None]


def potential_energies(forces: list[ParticleForce]) -> dict[str, float]:
    """``{energy key: potential energy (J)}`` of every registered kind (0 when not used)."""
    out = {kind.energy_key: 0.0 for kind in PARTICLE_FORCES}
    for f in forces:
        out[f.energy_key] = f.potential_energy()
    return out


def dissipated_energies(forces: list[ParticleForce]) -> dict[str, float]:
    """``{dissipation key: energy dissipated (J)}`` of every registered kind that dissipates
    (0 when not used)."""
    out = {kind.dissipation_key: 0.0 for kind in PARTICLE_FORCES if kind.dissipation_key}
    for f in forces:
        if f.dissipation_key:
            out[f.dissipation_key] = f.dissipated()
    return out
