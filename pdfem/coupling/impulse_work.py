"""The work of contact impulses on ice particles within one velocity-Verlet step, exactly.

Velocity Verlet changes a particle's kinetic energy over a step by the trapezoidal work
``1/2 (F_t + F_T) . (y_T - y_t)`` of its forces plus a bounded term that telescopes over the
steps. Impulses ``P_j`` that change the drift velocity at times ``tau_j`` inside the step add
``P . v_t + a_bar . sum_j P_j (tau_j - t) + |P|^2 / (2 m)`` to it (``P = sum_j P_j``,
``v_t`` the velocity at the step's start, ``a_bar`` the mean of the accelerations at its start
and end): derived by writing ``v_T = v_t + dt/2 (a_t + a_T) + P / m`` and
``y_T = y_t + dt v_t + dt^2/2 a_t + sum_j (T - tau_j) P_j / m``. With this as the contact's
work on the ice, the energy balance of a run closes to the integrators' own error. An impulse
at the step's start (``tau = t``) gives the seed scheme's ``m (v_t . dv + dv^2 / 2)``.
Units: kg, m/s, m/s^2, N s, J.
"""

from __future__ import annotations

import numpy as np


class ImpulseWork:
    """Collects the impulses one ice body's particles take during a step and returns their work.

    Parameters
    ----------
    body
        An ice body (:class:`pdfem.pd.ice_interface.IceParticles`: ``v``, ``f``, ``vol``,
        ``material.density``, ``gravity``, ``owned``), at the start of the step.
    """

    def __init__(self, body) -> None:
        rho = body.material.density
        self.mass = rho * body.vol
        self.v0 = body.v.copy()
        self.a0 = body.f / rho + np.asarray(body.gravity, dtype=np.float64)
        self.impulse = np.zeros_like(self.v0)   # P, N s
        self.moment = np.zeros_like(self.v0)    # sum_j P_j (tau_j - t), N s^2

    def add(self, impulse: np.ndarray, since: float) -> None:
        """Impulses (N, 3) (N s) given ``since`` seconds after the step's start."""
        self.impulse += impulse
        if since:
            self.moment += since * impulse

    def work(self, body) -> float:
        """The impulses' work (J) on the owned particles, with the body at the step's end."""
        rho = body.material.density
        a_bar = 0.5 * (self.a0 + body.f / rho + np.asarray(body.gravity, dtype=np.float64))
        p = self.impulse[body.owned]
        per = (np.einsum("ij,ij->i", p, self.v0[body.owned])
               + np.einsum("ij,ij->i", a_bar[body.owned], self.moment[body.owned])
               + 0.5 * np.einsum("ij,ij->i", p, p) / self.mass[body.owned])
        return float(per.sum())
