"""A moving (rotating and translating) frame that carries an elastic structure: its kinematics
and the inertial loads it puts on the elastic motion relative to it (docs/rotating_structures.md).

The frame turns about a fixed axis ``n`` through its centre at the angular speed
``s(t) |omega|`` and its centre moves at ``s(t) V``; ``s(t) = min(t / T, 1)`` ramps the speed
linearly from rest over ``ramp_time`` T (s), starting at t = 0 (T = 0: full speed at once).
A material point with reference position X and elastic displacement u_e (in frame axes) is at

    x = c(t) + R(t) (X - c0 + u_e),     c(t) = c0 + V S(t),  R(t) = rotation by theta(t) about n,

with ``S(t) = int_0^t s`` and ``theta(t) = |omega| S(t)``. Because the axis is fixed the frame's
angular velocity has the same components in the frame and in the world. The equation of the
elastic motion in frame axes gets the inertial (d'Alembert) loads, per lumped mass m,

    f = -m [ R^T a_c + w' x r + w x (w x r) + 2 w x u_e' ],     r = X - c0 + u_e,

(translation, Euler, centrifugal, Coriolis; ``a_c = s'(t) V``), evaluated by
:func:`pdfem.motion.frame_kernels.inertial_loads` from :meth:`MovingFrame.inertial_rates`.
SI units: m, s, rad, N.

Instead of ``velocity`` the centre may follow a piecewise-linear translation ``path`` (the same
``[[t, ux, uy, uz], ...]`` as a towed rigid hull's, :class:`pdfem.geometry.path.DisplacementPath`):
``c(t) = c0 + path(t)``; between its points the frame does not accelerate, and at a point its
velocity jumps (:meth:`MovingFrame.velocity_jump`), which the structure takes as a jump of u_e'
(the nodes keep their world velocity).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pdfem.geometry.path import DisplacementPath
from pdfem.geometry.vectors import cross
from pdfem.motion.rotation import axis_rotation


@dataclass(frozen=True)
class MovingFrame:
    """A frame turning about a fixed axis and translating, its speed ramped from rest.

    Parameters
    ----------
    angular_velocity
        (3,) final angular velocity (rad/s); its direction is the fixed shaft axis.
    center
        (3,) centre of rotation at t = 0 (m), a point of the shaft axis.
    velocity
        (3,) final velocity of the centre (m/s).
    ramp_time
        Time (s) over which the speeds rise linearly from 0, from t = 0 (0: at once).
    path
        Rows ``[t, ux, uy, uz]`` (s, m) of a piecewise-linear translation of the centre, instead
        of ``velocity``; ``None``: none.
    """

    angular_velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    ramp_time: float = 0.0
    path: tuple | None = None
    _last: dict = field(default_factory=dict, init=False, repr=False, compare=False)
    """The last :meth:`state` asked for (a substep asks for it several times at one time)."""

    @property
    def is_still(self) -> bool:
        """Whether the frame never moves (no rotation, no translation)."""
        return not (np.any(self.angular_velocity) or np.any(self.velocity)
                    or self.path is not None)

    def velocity_jump(self, t0: float, t1: float) -> np.ndarray:
        """(3,) jump (m/s, world) of the centre's velocity over ``(t0, t1]`` (s): the path's
        kinks there; zero without a path (the ramp is a finite acceleration)."""
        if self.path is None:
            return np.zeros(3)
        p = DisplacementPath(self.path)
        return p.velocity(t1) - p.velocity(t0)

    def speed_factor(self, t: float) -> tuple[float, float, float]:
        """``s(t)`` (-), ``s'(t)`` (1/s) and ``S(t) = int_0^t s`` (s) of the linear ramp."""
        T = self.ramp_time
        if T <= 0.0 or t >= T:
            return 1.0, 0.0, (t - 0.5 * T if T > 0.0 else t)
        if t <= 0.0:
            return 0.0, 1.0 / T, 0.0
        return t / T, 1.0 / T, 0.5 * t * t / T

    def angle(self, t: float) -> float:
        """Angle (rad) the frame has turned through about its axis by time ``t`` (s)."""
        return float(np.linalg.norm(self.angular_velocity)) * self.speed_factor(t)[2]

    def state(self, t: float) -> dict[str, np.ndarray]:
        """The frame at time ``t`` (s): ``R`` (3, 3) rotation, ``c`` (3,) centre (m), ``c_dot``
        (m/s), ``c_ddot`` (m/s^2), ``w`` and ``w_dot`` (3,) angular velocity (rad/s) and
        acceleration (rad/s^2), in world axes (``w``, ``w_dot`` are the same in frame axes).
        The arrays are shared with later calls at the same ``t``: read them, do not change them."""
        if self._last.get("t") == t:
            return self._last["state"]
        s, ds, S = self.speed_factor(t)
        w = np.asarray(self.angular_velocity, dtype=np.float64)
        V = np.asarray(self.velocity, dtype=np.float64)
        speed = float(np.linalg.norm(w))
        R = axis_rotation(w / speed, speed * S) if speed > 0.0 else np.eye(3)
        c, c_dot = V * S, s * V
        if self.path is not None:
            p = DisplacementPath(self.path)
            c, c_dot = c + p.displacement(t), c_dot + p.velocity(t)
        state = {"R": R, "c": np.asarray(self.center, dtype=np.float64) + c,
                 "c_dot": c_dot, "c_ddot": ds * V, "w": s * w, "w_dot": ds * w}
        self._last.update(t=t, state=state)
        return state

    def inertial_rates(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The frame's motion in frame axes at time ``t`` (s), as its inertial loads need it
        (:func:`pdfem.motion.frame_kernels.inertial_loads`): the centre's acceleration
        ``R^T c''`` (m/s^2), the angular acceleration and velocity (rad/s^2, rad/s; the same
        components in both axes, the axis being fixed)."""
        f = self.state(t)
        return f["R"].T @ f["c_ddot"], f["w_dot"], f["w"]

    def to_world(self, t: float, r: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World positions (m) and velocities (m/s), (N, 3), of nodes at ``r`` = X - c0 + u_e
        with relative velocities ``v`` = u_e' (frame axes)."""
        return world_motion(self.state(t), r, v)

    def frame_velocity(self, t: float, r: np.ndarray) -> np.ndarray:
        """(N, 3) world velocity (m/s) of the frame's points that coincide with the nodes at
        ``r`` = X - c0 + u_e (the drive's velocity there, without the elastic motion)."""
        return frame_point_velocity(self.state(t), r)


def world_motion(frame: dict, r: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World positions (m) and velocities (m/s), (N, 3), of nodes at ``r`` = X - c0 + u_e with
    relative velocities ``v`` = u_e' (frame axes), for a frame ``state`` (``R``, ``c``,
    ``c_dot``, ``w`` in world axes): ``c + R r`` and ``c' + w x (R r) + R v``."""
    rr = r @ frame["R"].T
    return frame["c"] + rr, frame["c_dot"] + cross(frame["w"], rr) + v @ frame["R"].T


def frame_point_velocity(frame: dict, r: np.ndarray) -> np.ndarray:
    """(N, 3) world velocity (m/s) of the frame's points at ``r`` (frame axes, from its centre),
    for a frame ``state``: ``c' + w x (R r)``."""
    return frame["c_dot"] + cross(frame["w"], r @ frame["R"].T)
