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

import numba
import numpy as np


@numba.njit(cache=True)
def impulse_work_terms(owned, impulse, moment, v0, f0, f, rho, gravity, mass):
    """Per owned particle (in index order), the work of its impulses over the step:
    ``P . v_t + a_bar . M + P . P / (2 m)`` with ``a_bar`` the mean of the accelerations
    ``f / rho + g`` at the step's start (``f0``) and end (``f``) and ``M = sum_j P_j (tau_j - t)``;
    0 for a particle that took no impulse. The three-term dot products are summed as
    ``(x0 + x2) + x1``, the order of numpy's ``einsum("ij,ij->i")`` that this kernel replaced
    (so runs keep their bits)."""
    n_owned = 0
    for i in range(owned.shape[0]):
        if owned[i]:
            n_owned += 1
    out = np.zeros(n_owned)
    k = 0
    for i in range(owned.shape[0]):
        if not owned[i]:
            continue
        p0, p1, p2 = impulse[i, 0], impulse[i, 1], impulse[i, 2]
        m0, m1, m2 = moment[i, 0], moment[i, 1], moment[i, 2]
        if p0 != 0.0 or p1 != 0.0 or p2 != 0.0 or m0 != 0.0 or m1 != 0.0 or m2 != 0.0:
            a0 = 0.5 * ((f0[i, 0] / rho + gravity[0]) + f[i, 0] / rho + gravity[0])
            a1 = 0.5 * ((f0[i, 1] / rho + gravity[1]) + f[i, 1] / rho + gravity[1])
            a2 = 0.5 * ((f0[i, 2] / rho + gravity[2]) + f[i, 2] / rho + gravity[2])
            pv = (p0 * v0[i, 0] + p2 * v0[i, 2]) + p1 * v0[i, 1]
            am = (a0 * m0 + a2 * m2) + a1 * m1
            pp = (p0 * p0 + p2 * p2) + p1 * p1
            out[k] = (pv + am) + 0.5 * pp / mass[i]
        k += 1
    return out


class ImpulseWork:
    """Collects the impulses one ice body's particles take during a step and returns their work.

    Parameters
    ----------
    body
        An ice body (:class:`pdfem.pd.ice_interface.IceParticles`: ``v``, ``f``,
        ``material.density``, ``gravity``, ``owned``), at the start of the step.
    mass
        Its particles' masses rho V (kg, (N,)), as the caller keeps them.

    A ledger is kept from step to step: :meth:`start` begins the next step's (its arrays are
    reused, and only the rows that took impulses are cleared), so a step costs two copies of
    the body's velocities and forces, not four new arrays.
    """

    def __init__(self, body, mass: np.ndarray) -> None:
        self.v0 = self.f0 = self.impulse = self.moment = np.zeros((0, 3))
        self._touched: list[np.ndarray] = []
        self.start(body, mass)

    def start(self, body, mass: np.ndarray) -> "ImpulseWork":
        """Begin the ledger of a new step of ``body`` (at its start; ``mass`` as above)."""
        self.mass = mass
        if self.v0.shape != body.v.shape:     # the first step, or the particles moved
            self.v0, self.f0 = np.empty_like(body.v), np.empty_like(body.f)
            self.impulse = np.zeros_like(self.v0)   # P, N s
            self.moment = np.zeros_like(self.v0)    # sum_j P_j (tau_j - t), N s^2
        else:
            for rows in self._touched:
                self.impulse[rows] = 0.0
                self.moment[rows] = 0.0
        self._touched = []
        np.copyto(self.v0, body.v)
        np.copyto(self.f0, body.f)
        return self

    def add(self, rows: np.ndarray, impulse: np.ndarray, since: float) -> None:
        """Impulses (K, 3) (N s) given to the particles ``rows`` (K,) (distinct) ``since``
        seconds after the step's start."""
        self._touched.append(rows)
        self.impulse[rows] += impulse
        if since:
            self.moment[rows] += since * impulse

    def work(self, body) -> float:
        """The impulses' work (J) on the owned particles, with the body at the step's end (0
        without an impulse in the step: every term is 0)."""
        if not self._touched:
            return 0.0
        per = impulse_work_terms(body.owned, self.impulse, self.moment, self.v0, self.f0, body.f,
                                 body.material.density,
                                 np.asarray(body.gravity, dtype=np.float64), self.mass)
        return float(per.sum())
