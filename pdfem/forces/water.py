"""Water on ice particles: buoyancy of the submerged part of each particle's cell and drag
against the velocity relative to the current (SI units; formulas in docs/water.md and
:mod:`pdfem.forces.water_kernels`).

Buoyancy is conservative: its potential energy (``water_potential``, J, zero at the reference
positions) is exact, the integral of the force over z. Drag is not: the energy it takes out
(``water_drag_dissipated``, J) is summed particle by particle over the moves between two force
evaluations by the trapezoid rule, which is how velocity Verlet applies a force over a step, so
the energy balance closes to the integrator's O(dt^2) error. With a current the drag can also
put energy in (the term is then negative). Under MPI the forces go to the owned particles and
every sum runs through the bodies' ``owned_sum``.

Added mass (optional, off by default) gives a submerged particle the inertia of the water it
carries along, ``Ca rho_w phi`` per unit volume: the water force, added last, rescales the
particle's total force so that velocity Verlet's kick gives the acceleration
``(f + rho_ice g) / (rho_ice + Ca rho_w phi)``. The water's kinetic energy (minus the work of
that rescaling on the ice, by the same trapezoid rule) is stored energy and is counted in
``water_potential``. Contact impulses from structures act on the ice's own mass.
"""

from __future__ import annotations

import numpy as np

from pdfem.forces.base import ParticleForce
from pdfem.forces.water_kernels import (Sea, added_mass_forces, buoyancy_potential, cell_sides,
                                       drag_work, water_forces)


class _BodyWater:
    """Per-body arrays of the water force: drag now and at the last evaluation, the positions
    then, and the drag dissipation of each particle (J)."""

    def __init__(self, body) -> None:
        n = body.y.shape[0]
        self.owned = np.ascontiguousarray(body.owned, dtype=np.uint8)
        self.side = np.empty(n)   # cell sides vol^(1/3), m
        cell_sides(np.ascontiguousarray(body.vol, dtype=np.float64), self.side)
        self.drag = np.zeros((n, 3))
        self.drag_prev = np.zeros((n, 3))
        self.y_prev: np.ndarray | None = None
        self.dissipated = np.zeros(n)
        self.potential = np.zeros(n)
        self.am = np.zeros((n, 3))
        self.am_prev = np.zeros((n, 3))
        self.water_kinetic = np.zeros(n)


class Water(ParticleForce):
    """Buoyancy and drag of still water (with a uniform current) on ice bodies.

    Parameters
    ----------
    bodies
        The ice bodies (:class:`pdfem.pd.ice_interface.IceParticles`).
    density
        Water density, kg/m^3.
    level
        z of the water surface, m.
    g
        Gravity magnitude, m/s^2 (gravity acts down z).
    current
        (3,) water velocity, m/s.
    linear_drag
        Damping rate of fully submerged ice, 1/s.
    drag_coefficient
        Quadratic drag coefficient Cd of a particle's cell, -.
    added_mass
        Added-mass coefficient Ca, -: a submerged particle's inertia is
        ``rho_ice + Ca rho_w phi`` (kg/m^3); 0 = off.
    """

    label = "water"
    energy_key = "water_potential"
    dissipation_key = "water_drag_dissipated"

    def __init__(self, bodies: list, *, density: float, level: float, g: float,
                 current=(0.0, 0.0, 0.0), linear_drag: float = 0.0,
                 drag_coefficient: float = 0.0, added_mass: float = 0.0) -> None:
        self.bodies = list(bodies)
        self.density, self.level, self.g = float(density), float(level), float(g)
        self.current = np.asarray(current, dtype=np.float64).reshape(3)
        self.linear_drag, self.drag_coefficient = float(linear_drag), float(drag_coefficient)
        self.added_mass = float(added_mass)
        self._drags = self.linear_drag > 0.0 or self.drag_coefficient > 0.0
        self._state = [_BodyWater(b) for b in self.bodies]
        self._sea = Sea(self.level, self.density, self.g, self.current, self.linear_drag,
                        self.drag_coefficient)

    def add_forces(self) -> None:
        """Add buoyancy and drag (N/m^3) into the bodies' ``f``; count the drag's work since the
        last call."""
        for b, s in zip(self.bodies, self._state):
            water_forces(b.y, b.v, s.side, s.owned, self._sea, float(b.material.density), b.f,
                         s.drag)
            if self.added_mass:
                added_mass_forces(b.y, s.side, s.owned, self.level, self.density,
                                  float(b.material.density), self.added_mass,
                                  np.asarray(b.gravity, dtype=np.float64), b.f, s.am)
            if not (self._drags or self.added_mass):  # buoyancy only: no work to count
                continue
            if s.y_prev is None:
                s.y_prev = b.y.copy()
                s.drag_prev[:] = s.drag
                if self.added_mass:
                    s.am_prev[:] = s.am
                continue
            # each work from y_prev; the last call moves y_prev on (and each its force)
            if self._drags:   # (drag_prev is read only here)
                drag_work(b.y, s.y_prev, b.vol, s.drag, s.drag_prev, s.dissipated,
                          not self.added_mass)
            if self.added_mass:
                drag_work(b.y, s.y_prev, b.vol, s.am, s.am_prev, s.water_kinetic, True)
        return None

    def potential_energy(self) -> float:
        """Energy (J) stored in the water, over all ranks: the buoyancy potential relative to
        the reference positions plus, with added mass, the kinetic energy of the water moving
        with the ice (minus the work of the added-mass force on the ice)."""
        total = 0.0
        for b, s in zip(self.bodies, self._state):
            buoyancy_potential(b.y, b.x0, b.vol, s.side, s.owned, self.level, self.density,
                               self.g, s.potential)
            total += float(b.owned_sum(s.potential + s.water_kinetic * s.owned))
        return total

    def dissipated(self) -> float:
        """Energy (J) the drag has taken out of the ice since the start, over all ranks."""
        return float(sum(b.owned_sum(s.dissipated * s.owned) for b, s in
                         zip(self.bodies, self._state)))

    _SAVED = ("dissipated", "water_kinetic", "drag_prev", "am_prev", "y_prev")

    def checkpoint_state(self) -> dict:
        """Per body ``k`` (in order) the drag loss ``dissipated_<k>`` and the water's kinetic
        energy ``water_kinetic_<k>`` per particle (J), the drag and added-mass forces at the
        last evaluation ``drag_prev_<k>``, ``am_prev_<k>`` (N/m^3) and the positions then
        ``y_prev_<k>`` (m), over this rank's owned particles, whose global numbers are
        ``gid_<k>`` (not collective), so that a restart on any number of ranks continues the
        energy history (bit for bit on as many)."""
        out: dict = {}
        for k, (b, s) in enumerate(zip(self.bodies, self._state)):
            own = np.asarray(b.owned, dtype=bool)
            out[f"gid_{k}"] = b.owned_reference()[0]
            for key in self._SAVED:
                values = getattr(s, key)
                out[f"{key}_{k}"] = (b.y if values is None else values)[own]
        return out

    def moving_state(self, body) -> dict:
        """The counters kept between steps (:attr:`_SAVED`) of ``body``'s local particles."""
        s = self._state[self._index(body)]
        return {key: (body.y if getattr(s, key) is None else getattr(s, key))
                for key in self._SAVED}

    def moved_state(self, body, state: dict) -> None:
        """The counters of ``body``'s particles after a re-partition, in its new local order."""
        k = self._index(body)
        s = self._state[k] = _BodyWater(body)
        s.y_prev = body.y.copy()
        for key in self._SAVED:
            getattr(s, key)[:] = state[key].reshape(getattr(s, key).shape)

    def _index(self, body) -> int:
        return next(k for k, b in enumerate(self.bodies) if b is body)

    def restore_state(self, state: dict) -> None:
        """Put a state from :meth:`checkpoint_state` back into the owned particles: per body
        ``k`` the arrays ``<key>_<k>`` in the body's local particle order (the checkpoint's
        parts picked by :mod:`pdfem.run.checkpoint_ranks`)."""
        for k, (b, s) in enumerate(zip(self.bodies, self._state)):
            own = np.asarray(b.owned, dtype=bool)
            if s.y_prev is None:
                s.y_prev = b.y.copy()
            for key in self._SAVED:
                saved = np.asarray(state[f"{key}_{k}"], dtype=np.float64)
                target = getattr(s, key)
                if saved.shape != target.shape:
                    raise ValueError(f"water on ice body '{b.name}': {key} has shape "
                                     f"{saved.shape} in the checkpoint, {target.shape} here")
                target[own] = saved[own]

    def submerged_volumes(self) -> list[float]:
        """Submerged volume of each body (m^3, over all ranks): sum of vol * phi."""
        out = []
        for b, s in zip(self.bodies, self._state):
            a = np.cbrt(b.vol)
            phi = np.clip((self.level - b.y[:, 2] + 0.5 * a) / a, 0.0, 1.0)
            out.append(float(b.owned_sum(b.vol * phi * s.owned)))
        return out

    def out_of_equilibrium(self, tolerance: float = 0.02) -> list[str]:
        """Messages for the bodies whose buoyancy differs from their weight by more than
        ``tolerance`` of it at the current positions (they will heave; a level sheet of
        thickness h floats with its bottom at ``level - (rho_ice / rho_water) h``)."""
        out = []
        for b, wet in zip(self.bodies, self.submerged_volumes()):
            rho = float(b.material.density)
            volume = float(b.owned_sum(b.vol * (b.owned > 0)))
            need = rho * volume / self.density  # submerged volume at equilibrium, m^3
            if abs(wet - need) > tolerance * need:
                out.append(f"ice body '{b.name}' starts out of hydrostatic equilibrium: "
                           f"{wet:.4g} m^3 of it is under water, floating needs {need:.4g} m^3 "
                           f"(rho_ice / rho_water = {rho / self.density:.4f} of its volume); "
                           "it will heave (place a level sheet of thickness h with its bottom at "
                           "water.level - (rho_ice / rho_water) h to start at rest)")
        return out
