"""Gravity on ice particles: a uniform acceleration g (m/s^2).

Gravity enters velocity Verlet's kick as an acceleration, ``v += dt/2 (f / rho + g)``, exactly as
the bodies integrate it (:meth:`pdfem.pd.body.IceBody.begin_step`): :class:`Gravity` sets the
bodies' uniform body acceleration ``gravity`` and adds nothing to ``f`` (adding ``rho g`` to the
force density and dividing by ``rho`` again would round differently). Its potential energy
relative to the reference positions is ``-sum rho V (y - x0) . g``.
"""

from __future__ import annotations

import numpy as np

from pdfem.forces.base import ParticleForce


class Gravity(ParticleForce):
    """A uniform gravity field on ice bodies.

    Parameters
    ----------
    bodies
        The ice bodies (:class:`pdfem.pd.ice_interface.IceParticles`); their ``gravity`` is set.
    g
        (3,) gravitational acceleration, m/s^2.
    """

    label = "gravity"
    energy_key = "gravity_potential"

    def __init__(self, bodies: list, g) -> None:
        self.bodies = list(bodies)
        self.g = np.asarray(g, dtype=np.float64).reshape(3)
        for b in self.bodies:
            b.gravity = self.g.copy()

    def add_forces(self) -> None:
        """Nothing: gravity acts through the bodies' kick (see the module docstring)."""
        return None

    def potential_energy(self) -> float:
        """``-sum rho V (y - x0) . g`` over the owned particles of all bodies (J)."""
        return sum(self.body_potential(b) for b in self.bodies)

    @staticmethod
    def body_potential(body) -> float:
        """Potential energy (J) of one body in its gravity field (0 without gravity)."""
        if not np.any(body.gravity):
            return 0.0
        u = body.y - body.x0
        return -body.material.density * float(body.owned_sum(body.vol * (u @ body.gravity)))
