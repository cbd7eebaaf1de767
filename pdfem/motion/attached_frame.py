"""An elastic structure riding on a free ship: its frame is the ship's pose, and the load it
carries reaches the ship through its supports (an elastic bow panel, docs/icebreaking.md).

:class:`ShipFrame` has the interface of :class:`pdfem.motion.moving_frame.MovingFrame` with the
kinematics read from a :class:`pdfem.motion.ship.Ship` instead of prescribed: a material point
with mesh position X (the hull's mesh coordinates) and elastic displacement u_e (ship body
axes) is at ``x = c + R (X - c_G + u_e)``, with c the ship's centre of gravity, R its attitude
and c_G its centre of gravity in the mesh. The inertial loads on the elastic motion use the
ship's acceleration and angular acceleration averaged over its last step (its velocity change
since its previous step, ice impulses included), in body axes::

    f = -m [ R^T a_G + w_b' x r + w_b x (w_b x r) + 2 w_b x u_e' ],    w_b = R^T w.

Ordering: the ship steps before the structure that rides on it (the builder puts it first,
:func:`pdfem.run.build_structures.build_all`), so in every
(sub)step the ship has reached ``t + h`` when the structure steps to ``t + h`` (its inertial
loads use the ship's state at the step's end, as a moving frame's do); the acceleration is the
ship's mean over that step (a lag of half a step).

:class:`AttachedStructure` is a :class:`pdfem.motion.frame_structure.FrameStructure` in such a frame.
The ship's mass includes the structure (its rigid motion is the ship's); the structure's
elastic motion adds the momentum ``P_e = sum m R u_e'`` (world axes). After every step the
structure gives the ship, at each node, the impulse of the external loads it received since
the last hand-over (contact impulses, applied loads) minus the change of its elastic momentum
there: ``j_i = J_ext,i - (p_i(now) - p_i(before))``, ``p_i = m_i R u_e,i'``. That is the load
its supports pass on to the hull (what the plating does not keep in its own motion), so the
momentum of ship + structure changes by exactly the external impulses (tests/coupling/test_bow_panel.py).
Energy: the ship books the work of these impulses (its kinetic-energy change) as its
``support_work``, the structure books the work of its frame's inertial loads and of the
contact impulses on the frame's velocity as its own (as for any moving frame); the two are the
exchange between hull and panel and cancel up to the integrators' O(h) differences (reported
as ``drive_work`` of the panel and ``attached_work`` of the ship). SI units throughout.
"""

from __future__ import annotations

import numpy as np

from pdfem.fem.central_difference_kernels import trapezoid_work
from pdfem.motion.frame_structure import FrameStructure
from pdfem.motion.moving_frame import frame_point_velocity, world_motion
from pdfem.motion.rotation import rotation_vector
from pdfem.motion.ship import Ship


class ShipFrame:
    """The moving frame of a structure riding on ``ship`` (see the module docstring).

    Parameters
    ----------
    ship
        The free ship; its state is read each time (no copy).
    """

    angular_velocity = (0.0, 0.0, 0.0)   # no prescribed spin: no centrifugal prestress
    velocity = (0.0, 0.0, 0.0)
    ramp_time = 0.0
    is_still = False

    def __init__(self, ship: Ship) -> None:
        self.ship = ship
        self.center = tuple(float(c) for c in ship.cg_mesh)

    def speed_factor(self, t: float) -> tuple[float, float, float]:
        """``(1, 0, t)``: the frame is always at its full (the ship's) speed."""
        return 1.0, 0.0, t

    def velocity_jump(self, t0: float, t1: float) -> np.ndarray:
        """Zero: the ship's velocity changes enter through its mean acceleration."""
        return np.zeros(3)

    def angle(self, t: float) -> float:
        """The ship's rotation angle (rad) from the mesh's attitude now."""
        return float(np.linalg.norm(rotation_vector(self.ship.q)))

    def state(self, t: float) -> dict[str, np.ndarray]:
        """The ship now: ``R`` (3, 3), ``c`` (m), ``c_dot`` (m/s), ``c_ddot`` (m/s^2), ``w``
        (rad/s) and ``w_dot`` (rad/s^2), world axes (``t`` is not used: the ship is at the
        time the structure needs, see the module docstring)."""
        s = self.ship
        return {"R": s.R, "c": s.c, "c_dot": s.v, "c_ddot": s.acceleration, "w": s.omega,
                "w_dot": s.angular_acceleration}

    def inertial_rates(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The ship's motion in body axes now, as the inertial loads need it
        (:func:`pdfem.motion.frame_kernels.inertial_loads`): ``R^T a_G`` (m/s^2),
        ``R^T w'`` (rad/s^2) and ``R^T w`` (rad/s)."""
        f = self.state(t)
        R = f["R"]
        return R.T @ f["c_ddot"], R.T @ f["w_dot"], R.T @ f["w"]

    def to_world(self, t: float, r: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World positions (m) and velocities (m/s) of nodes at ``r`` with relative velocities
        ``v`` (body axes)."""
        return world_motion(self.state(t), r, v)

    def frame_velocity(self, t: float, r: np.ndarray) -> np.ndarray:
        """(N, 3) world velocity (m/s) of the hull's points at the nodes ``r``."""
        return frame_point_velocity(self.state(t), r)


class AttachedStructure(FrameStructure):
    """An elastic structure riding on a ship, handing its support loads to the ship.

    Parameters
    ----------
    *args, **kwargs
        As for :class:`pdfem.fem.structure.ElasticStructure`.
    ship
        The ship it is attached to (stepped before it in the run).
    """

    def __init__(self, *args, ship: Ship, **kwargs):
        super().__init__(*args, frame=ShipFrame(ship), stress_stiffening=False, **kwargs)
        self.ship = ship
        self._pending = np.zeros((self.n_nodes, 3))   # N s, world: external impulses not yet handed
        self._p = self._elastic_momentum()             # kg m/s per node, world
        self._f_load = self.external_force_dofs(0.0)   # N, body axes: applied + contact forces
        self._R = ship.R.copy()

    def _elastic_momentum(self) -> np.ndarray:
        """(Nn, 3) m u_e' per node in world axes (kg m/s)."""
        mv = self.dofmap.to_nodal(self.solver.m * self.solver.v)
        return mv @ self.frame.state(0.0)["R"].T

    def step(self, dt: float) -> None:
        """Advance by ``dt`` (s) as a moving-frame structure, then hand the ship the impulse of
        its supports (see the module docstring)."""
        t_new = self.solver.time + dt
        f_load = self.external_force_dofs(t_new)
        f_in = self._inertial_dofs(t_new)
        u_old = self.solver.u
        self.solver.step(dt, f_load + f_in)
        self.inertial_work += trapezoid_work(self._f_inertial, f_in, self.solver.u, u_old)
        self._f_inertial = f_in
        R = self.ship.R
        self._pending += 0.5 * dt * (self.dofmap.to_nodal(self._f_load) @ self._R.T
                                     + self.dofmap.to_nodal(f_load) @ R.T)
        self._f_load, self._R = f_load, R.copy()
        p = self._elastic_momentum()
        j = self._pending - (p - self._p)
        x, _ = self.frame.to_world(t_new, self.relative_motion()[0], np.zeros_like(p))
        self.ship.apply_attached_impulse(x, j)
        self._p, self._pending = p, np.zeros_like(p)

    def apply_surface_impulse(self, impulse: np.ndarray) -> float:
        """As :meth:`FrameStructure.apply_surface_impulse`; the impulses (world) are also kept
        for the next hand-over to the ship (those on supported nodes go on to it whole)."""
        j = np.asarray(impulse, dtype=np.float64).reshape(-1, 3)
        np.add.at(self._pending, self.surface_nodes, j)
        return super().apply_surface_impulse(j)

    def checkpoint_state(self) -> dict[str, np.ndarray | float]:
        """The moving-frame structure's state plus the pending hand-over."""
        out = super().checkpoint_state()
        out.update(pending=self._pending.copy(), p_elastic=self._p.copy(),
                   f_load=self._f_load.copy(), R_load=self._R.copy())
        return out

    def restore_state(self, state: dict) -> None:
        """Restore a state from :meth:`checkpoint_state` exactly."""
        super().restore_state(state)
        self._pending = np.array(state["pending"], dtype=np.float64)
        self._p = np.array(state["p_elastic"], dtype=np.float64)
        self._f_load = np.array(state["f_load"], dtype=np.float64)
        self._R = np.array(state["R_load"], dtype=np.float64)

    def describe(self) -> str:
        """As :meth:`ElasticStructure.describe`, with the ship it rides on."""
        base = super(FrameStructure, self).describe()
        return f"{base}; attached to ship '{self.ship.name}' (moves with its hull)"
