"""Prescribed motions of ice particles (supports, drivers), their reactions and their work.

A :class:`VelocityConstraint` is a named region of particles that stays fixed, moves with a
velocity (ramped linearly from 0 over ``ramp_time``) or follows a displacement path
(:class:`pdfem.geometry.path.DisplacementPath`). Its reaction, the force (N) that the support or
driver exerts on the ice, is what keeps its particles on the prescribed motion::

    R = sum_i V_i (rho a_prescribed - f_i - rho g)      (summed over every process)

(``f`` force density N/m^3 at the current positions, ``g`` the body's uniform acceleration;
contact impulses on the region's own particles are not in it). On a path the particles drift
with the path's mean velocity over each step and are put on x0 + u(t) at its end, so they follow
the path to round-off; their velocity is the slope of the path's current segment. The work a
constraint does over a velocity-Verlet step from t0 to t1 is counted exactly as the energy it
puts into its particles, so the energy balance closes also where a path's velocity jumps (at its
points)::

    W = 1/2 m (|v(t1)|^2 - |v(t0)|^2) - 1/2 (F(t0) + F(t1)) . (y(t1) - y(t0))

with ``m = rho sum V_i`` and ``F = sum_i V_i (f_i + rho g)``: the kinetic energy the driver gives
its particles minus the trapezoidal work of the other forces on them. For a constant velocity this
is the trapezoidal integral of the power R . v. Under MPI ``index`` holds a rank's owned local
particles; a re-partition (:mod:`pdfem.pd.layout.migration`) moves each particle's membership with it
and rebuilds the lists. Units: SI.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pdfem.geometry.path import DisplacementPath
from pdfem.pd.integrate import place_rows, set_rows


@dataclass
class VelocityConstraint:
    """Particles ``index`` move with ``velocity`` (m/s) scaled by min(1, t / ramp_time), or (if
    ``path`` is given) follow its displacement; ``name`` names the region's reaction."""

    index: np.ndarray
    velocity: np.ndarray
    ramp_time: float = 0.0
    path: DisplacementPath | None = None
    name: str = ""

    @property
    def moves(self) -> bool:
        """Whether the particles move (False: a fixed region, whose work is zero)."""
        return self.path is not None or bool(np.any(self.velocity))

    def impose(self, body, t: float, step: float = 0.0) -> None:
        """Put the particles of ``body`` on the motion at ``t`` (s): their velocity and, for a
        path, their position (x0 + u(t): exact, no round-off gathered over the steps); with
        ``step`` (s), only the velocity of the drift over ``[t, t + step]``."""
        if step:
            set_rows(body.v, self.index, self.drift(t, step))
            return
        set_rows(body.v, self.index, self.value(t))
        if self.path is not None:
            place_rows(body.y, body.x0, self.index, self.path.displacement(t))

    def value(self, t: float) -> np.ndarray:
        """The prescribed velocity (m/s) at time ``t`` (s)."""
        if self.path is not None:
            return self.path.velocity(t)
        s = 1.0 if self.ramp_time <= 0.0 else min(1.0, max(t, 0.0) / self.ramp_time)
        return self.velocity * s

    def drift(self, t: float, step: float) -> np.ndarray:
        """The velocity (m/s) of the drift over ``[t, t + step]`` (s): a path's mean velocity
        over it (so the particles land on the path), else the velocity at its middle."""
        if self.path is not None:
            return self.path.mean_velocity(t, t + step)
        return self.value(t + 0.5 * step)

    def acceleration(self, t: float) -> np.ndarray:
        """The prescribed acceleration (m/s^2) at time ``t`` (s) (zero on a path's segments)."""
        if self.path is None and self.ramp_time > 0.0 and t < self.ramp_time:
            return self.velocity / self.ramp_time
        return np.zeros(3)


def next_name(constraints: list, prefix: str) -> str:
    """``prefix<k>`` with the smallest k >= 1 that no constraint is named yet."""
    names = {c.name for c in constraints}
    k = 1
    while f"{prefix}{k}" in names:
        k += 1
    return f"{prefix}{k}"


def applied_forces(body) -> np.ndarray:
    """(k, 3) force F = sum_i V_i (f_i + rho g) (N) of the bond and body forces on the particles
    of each of ``body.constraints`` (an ice body's local arrays: ``f`` N/m^3, ``vol`` m^3)."""
    rho, out = body.material.density, np.zeros((len(body.constraints), 3))
    for k, c in enumerate(body.constraints):
        vol = body.vol[c.index]
        out[k] = vol @ body.f[c.index] + (rho * float(vol.sum())) * body.gravity
    return out


def reaction_forces(body) -> np.ndarray:
    """(k, 3) reaction R = (rho sum_i V_i) (a - g) - sum_i V_i f_i (N) of each of
    ``body.constraints`` at ``body.time``: the force its support or driver exerts on the ice,
    summed over the region's particles on every process, correctly rounded (the body's layout:
    the same on 1 and N ranks; collective)."""
    cs = body.constraints
    # per region sum_i V_i and sum_i V_i f_i, all in one pass and one collective
    sums = body.layout.weighted_sums(body.vol, body.f, [c.index for c in cs])
    accelerations = np.array([c.acceleration(body.time) for c in cs]).reshape(len(cs), 3)
    mass = body.material.density * sums[:, 0]
    return mass[:, None] * (accelerations - body.gravity) - sums[:, 1:]


def step_work(body, force0: np.ndarray, dt: float) -> float:
    """Work (J) of ``body.constraints`` over the step of ``dt`` (s) that ends at ``body.time``,
    given :func:`applied_forces` at its start (see the module docstring)."""
    rho, t0, work = body.material.density, body.time - dt, 0.0
    force1 = applied_forces(body)
    for k, c in enumerate(body.constraints):
        if not c.moves:
            continue
        v0, v1 = c.value(t0), c.value(body.time)
        mass = rho * float(body.vol[c.index].sum())
        work += (0.5 * mass * (float(v1 @ v1) - float(v0 @ v0))
                 - 0.5 * float((force0[k] + force1[k]) @ (dt * c.drift(t0, dt))))
    return work
