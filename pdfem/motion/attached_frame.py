"""An elastic structure riding on a free ship (an elastic bow panel, a deck plate,
docs/ship.md and docs/icebreaking.md): its frame is the ship's pose, and the ship and the
structure advance as one system, stable for any share of the ship's mass the structure carries.

:class:`ShipFrame` has the interface of :class:`pdfem.motion.moving_frame.MovingFrame` with the
kinematics read from a :class:`pdfem.motion.ship.Ship` instead of prescribed: a material point
with mesh position X (the hull's mesh coordinates) and elastic displacement u_e (ship body
axes) is at ``x = c + R (X - c_G + u_e)``, with c the ship's centre of gravity G, R its
attitude and c_G its centre of gravity in the mesh. The inertial loads on the elastic motion
are those of the ship's acceleration at the same instant (:attr:`pdfem.motion.ship.Ship.rates`,
body axes)::

    f = -m [ A_b + w_b' x r + w_b x (w_b x r) + 2 w_b x u_e' ].

The split (the "floating frame of reference" of flexible multibody dynamics, e.g. Shabana,
*Dynamics of Multibody Systems*, ch. 5): the ship is a case input of the whole ship, the
structure included (:mod:`pdfem.motion.attached_step`). The degrees of freedom the
structure's supports hold move with the hull, so the ship integrates the hull and them as one
rigid body; the free ones are the structure's own. They interact through forces alone: the
ship's body receives, at the end of each (sub)step, ``K u_e + C u_e'`` of every free degree of
freedom (the support loads: equal and opposite to what the structure's stiffness and damping
put on its free nodes, at the nodes' positions) and the applied loads of the held ones
(:meth:`AttachedStructure.begin_coupled_step`); its accelerations then follow from its own
6 x 6 mass matrix, and the structure's free nodes take them as inertial loads
(:meth:`AttachedStructure.end_coupled_step`). The ship orders the step
(:meth:`pdfem.motion.ship.Ship.step`): its half kick and drift, the structure's, the support
loads, the ship's second half kick, the structure's. Both sides kick with the same
acceleration at the same instant, so in world coordinates the free nodes follow central
differences with their own forces only: no lagged acceleration hands inertia from one side to
the other (the instability of an explicit hand-over once the structure's inertia is a sizeable
part of the ship's), and the step is stable below the assembly's own limit
(:func:`pdfem.motion.attached_step.assembly_max_eigenvalue`).

Impulses: a contact impulse on a free node jumps its velocity (work: its world kinetic-energy
change ``w . J + J^2 / (2 m)``); one on a held degree of freedom goes to the ship at once
(:meth:`pdfem.motion.ship.Ship.apply_impulse_at`). When the ship's velocity jumps (an impulse,
its held surge speed), the free nodes keep their world velocity
(:meth:`AttachedStructure.keep_world_velocity`).

Energy (each body books its own; the exchange between them is internal): the structure's
kinetic energy is the world kinetic energy of its free degrees of freedom (the held ones are
in the ship's), its strain energy ``u_e . K u_e / 2``, its ``load_work`` the work of its
applied loads in the world (trapezoid rule on the nodes' world displacements), its damping loss
the integrator's, and its ``kinetic_correction`` the central differences' ``-(h^2/8) a . M a``
with the free nodes' world accelerations ``a = (f - K u_e - C u_e') / m``. Without rotation the
pair is central differences in world coordinates and the balance of ship and structure closes to
round-off (less the ship's hydrostatics, whose potential the trapezoid rule follows to
O(h^2)). Diagnostics: the structure's ``drive_work`` (the inertial loads' work on its elastic
motion), the ship's ``attached_work`` (the support loads' work on the hull) and
``attached_impulse`` (:meth:`AttachedStructure.handed_impulse`). SI units throughout.
"""

from __future__ import annotations

import numpy as np

from pdfem.errors import InstabilityError
from pdfem.fem.central_difference_kernels import trapezoid_work
from pdfem.geometry.vectors import cross
from pdfem.motion.attached_step import rigid_rows
from pdfem.motion.frame_structure import FrameStructure
from pdfem.motion.moving_frame import frame_point_velocity, world_motion
from pdfem.motion.rigid_inertia import dof_inertia
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
        """Zero: the ship's velocity jumps reach the structure through
        :meth:`AttachedStructure.keep_world_velocity`."""
        return np.zeros(3)

    def angle(self, t: float) -> float:
        """The ship's rotation angle (rad) from the mesh's attitude now."""
        return float(np.linalg.norm(rotation_vector(self.ship.q)))

    def state(self, t: float) -> dict[str, np.ndarray]:
        """The ship now: ``R`` (3, 3), ``c`` (m), ``c_dot`` (m/s), ``c_ddot`` (m/s^2), ``w``
        (rad/s) and ``w_dot`` (rad/s^2), world axes (``t`` is not used: the ship is at the
        time the structure needs, see the module docstring)."""
        s = self.ship
        acc, w_dot, _ = s.rates
        return {"R": s.R, "c": s.c, "c_dot": s.v, "c_ddot": s.R @ acc, "w": s.omega,
                "w_dot": s.R @ w_dot}

    def inertial_rates(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The ship's motion in body axes now, as the inertial loads need it
        (:func:`pdfem.motion.frame_kernels.inertial_loads`): the acceleration of G (m/s^2),
        the angular acceleration (rad/s^2) and velocity (rad/s)
        (:attr:`pdfem.motion.ship.Ship.rates`)."""
        return self.ship.rates

    def to_world(self, t: float, r: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World positions (m) and velocities (m/s) of nodes at ``r`` with relative velocities
        ``v`` (body axes)."""
        return world_motion(self.state(t), r, v)

    def frame_velocity(self, t: float, r: np.ndarray) -> np.ndarray:
        """(N, 3) world velocity (m/s) of the hull's points at the nodes ``r``."""
        return frame_point_velocity(self.state(t), r)


class AttachedStructure(FrameStructure):
    """An elastic structure riding on a ship, advanced by the ship with it (module docstring).

    Parameters
    ----------
    *args, **kwargs
        As for :class:`pdfem.fem.structure.ElasticStructure`.
    ship
        The ship it is attached to; it steps the structure in its own step.

    Raises
    ------
    pdfem.motion.ship.InertiaError
        If the structure (with the ship's other riders) carries more mass or inertia than the
        whole ship's (:meth:`pdfem.motion.ship.Ship.attach`).
    """

    def __init__(self, *args, ship: Ship, **kwargs):
        super().__init__(*args, frame=ShipFrame(ship), stress_stiffening=False, **kwargs)
        self.ship = ship
        self._free_nodal = self.dofmap.to_nodal(self.solver.free.astype(np.float64)) > 0.5
        self._surface_held = ~self._free_nodal[self.surface_nodes]
        self.load_work = 0.0
        self._external_impulse = np.zeros(3)   # N s, world: applied loads and contact so far
        self._f_load = np.zeros(self.dofmap.n_dofs)   # N, body axes: applied loads now
        self._next_load = self._f_load
        self._started = None
        self._maa = 0.0   # kg m^2/s^4: sum of m a^2 of the free DOFs' world accelerations
        self._p0 = np.zeros(3)
        self._own_eigenvalue = self.solver.max_eigenvalue()   # 1/s^2, supports held still
        self._world_now()
        ship.attach(self)

    # ------------------------------------------------------------------ for the ship
    def inertia_about(self, point) -> tuple[np.ndarray, np.ndarray]:
        """(6, 6) mass matrices (body axes) about ``point`` (m, in the mesh) of all the
        structure's degrees of freedom and of its free ones
        (:func:`pdfem.motion.rigid_inertia.dof_inertia`)."""
        r = self.node_points - np.asarray(point, dtype=np.float64)
        return (dof_inertia(r, self.node_mass, np.ones_like(self._free_nodal)),
                dof_inertia(r, self.node_mass, self._free_nodal))

    def coupling_parts(self, point) -> tuple:
        """``K`` (N/m), the free-DOF mask, the lumped masses (kg) and the rigid rows ``T``
        about ``point`` (:func:`pdfem.motion.attached_step.rigid_rows`), for the stable step."""
        r = self.node_points - np.asarray(point, dtype=np.float64)
        return self.K, self.solver.free, self.solver.m, rigid_rows(r, self._dofs)

    def set_max_eigenvalue(self, value: float) -> None:
        """Take ``value`` (1/s^2), the assembly's ``omega_max^2``, for the stable step, or the
        structure's own with its supports held still if that estimate is larger (both power
        iterations approach from below, and the assembly's is at least the structure's own)."""
        self.solver.set_max_eigenvalue(max(value, self._own_eigenvalue))

    def _support_loads(self, u: np.ndarray, internal: np.ndarray,
                       load: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Force (N) and moment about G (N m), world axes, that the structure at the elastic
        displacement ``u`` puts on the ship's body: ``internal`` (``K u + C u'``) of its free
        DOFs and ``load`` of its held ones (DOF vectors, body axes)."""
        q = self.dofmap.to_nodal(np.where(self.solver.free, internal, load))
        r = self._r0 + self.dofmap.to_nodal(u)
        R = self.ship.R
        return R @ q.sum(axis=0), R @ cross(r, q).sum(axis=0)

    def support_loads_now(self) -> tuple[np.ndarray, np.ndarray]:
        """The support loads now (:meth:`_support_loads`), for the ship's start."""
        s = self.solver
        return self._support_loads(s.u, s.stiffness_force() + s.f_damp, self._f_load)

    def restart(self) -> None:
        """The accelerations now with the ship's (after the ship changed)."""
        self._f_load = self.external_force_dofs()
        self._f_inertial = self._inertial_dofs(self.solver.time)
        s = self.solver
        s.initialize(s.u, s.v, self._f_load + self._f_inertial, s.time)
        self._maa = self._world_acceleration_sum()
        self._world_now()
        self._p0 = self._elastic_momentum()

    def begin_coupled_step(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """The first half of a step of ``dt`` (s) with the ship at the step's end (its pose):
        the half kick and the drift; returns the support loads there (N, N m about G, world)."""
        s = self.solver
        self._started = s.begin_step(dt)
        self._next_load = self.external_force_dofs(s.time + dt)
        st = self._started
        return self._support_loads(st.u, st.ku + st.f_damp, self._next_load)

    def end_coupled_step(self) -> None:
        """End the step with the ship's accelerations at its end (:attr:`Ship.rates`).

        Raises
        ------
        InstabilityError
            If the displacement becomes NaN or infinite.
        """
        st, self._started = self._started, None
        f_in = self._inertial_dofs(self.solver.time + st.dt, st.u, st.v_half)
        u_old = self.solver.u
        self.solver.end_step(self._next_load + f_in)
        self.inertial_work += trapezoid_work(self._f_inertial, f_in, self.solver.u, u_old)
        self._f_inertial, self._f_load = f_in, self._next_load
        self._maa = self._world_acceleration_sum()
        x0, f0 = self._x_world, self._f_world
        self._world_now()
        f = f0 + self._f_world
        self.load_work += 0.5 * float(np.sum(f * (self._x_world - x0)))
        self._external_impulse += 0.5 * st.dt * f.sum(axis=0)
        if not np.isfinite(self.solver.u).all():
            raise InstabilityError(
                f"structure '{self.name}' (attached to ship '{self.ship.name}'): displacement "
                f"became non-finite at t = {self.solver.time:.6e} s; the step {st.dt:.3e} s "
                f"exceeds the stable step {self.stable_time_step():.3e} s or the loads are "
                "unbounded")

    def keep_world_velocity(self, dv: np.ndarray, dw: np.ndarray) -> None:
        """The ship's velocity jumped by ``dv`` (m/s, at G) and ``dw`` (rad/s), world axes:
        the free nodes keep their world velocity (their velocity relative to the hull jumps
        by minus the hull's there)."""
        R = self.ship.R
        r = self._r0 + self.dofmap.to_nodal(self.solver.u)
        jump = self.dofmap.to_dofs(R.T @ dv + cross(R.T @ dw, r))
        free = self.solver.free
        self.solver.v[free] -= jump[free]

    def step(self, dt: float) -> None:
        """Nothing: the ship it rides on took this step with it (:meth:`Ship.step`; the run
        steps the ship first).

        Raises
        ------
        RuntimeError
            If the ship has not taken the step (a structure stepped on its own).
        """
        if self.solver.time != self.ship.time:
            raise RuntimeError(f"structure '{self.name}' rides on ship '{self.ship.name}' and "
                               "is stepped by it: step the ship")

    # ------------------------------------------------------------------ energies, impulses
    def _world_now(self) -> None:
        """World node positions (m) and applied loads (N) now, for the loads' work."""
        r, v = self.relative_motion()
        self._x_world, _ = self.frame.to_world(self.solver.time, r, v)
        self._f_world = self.dofmap.to_nodal(self._f_load) @ self.ship.R.T

    def _world_acceleration_sum(self) -> float:
        """``sum m a^2`` (kg m^2/s^4) of the free DOFs' world accelerations, ``a = (f - K u_e
        - C u_e') / m``: the relative ones less the inertial loads' share."""
        s = self.solver
        a = np.where(s.free, s.a - self._f_inertial / s.m, 0.0)
        return float(a @ (s.m * a))

    def _elastic_momentum(self) -> np.ndarray:
        """(3,) ``sum m R u_e'`` (kg m/s, world)."""
        return self.ship.R @ self.dofmap.to_nodal(self.solver.m * self.solver.v).sum(axis=0)

    def handed_impulse(self) -> np.ndarray:
        """(3,) impulse (N s, world) passed on to the ship as a whole so far: the impulses of
        the applied loads and contacts on the structure less the change of its elastic
        momentum (what the plating does not keep in its own motion)."""
        return self._external_impulse - (self._elastic_momentum() - self._p0)

    def kinetic_energy(self) -> float:
        """World kinetic energy (J) of the free degrees of freedom (the held ones move with
        the hull: the ship books theirs)."""
        r, v = self.relative_motion()
        R, f = self.ship.R, self.frame.state(self.solver.time)
        w = R.T @ f["c_dot"] + cross(R.T @ f["w"], r) + v    # world velocity, body axes
        return 0.5 * float(np.sum(self.node_mass[:, None] * np.where(self._free_nodal, w * w,
                                                                      0.0)))

    def apply_surface_impulse(self, impulse: np.ndarray) -> float:
        """Contact impulses (N s, (Ns, 3), world axes): on free DOFs a jump of their velocity,
        on held ones an impulse on the ship at the node; returns their work (J), the world
        kinetic-energy change (module docstring)."""
        j = np.asarray(impulse, dtype=np.float64).reshape(-1, 3)
        self._external_impulse += j.sum(axis=0)
        R = self.ship.R
        jb = j @ R
        held = np.where(self._surface_held, jb, 0.0)
        free = jb - held
        r = self._surface_relative()
        vf = R.T @ self.ship.v + cross(R.T @ self.ship.omega, r)   # the hull there, body axes
        work = self.solver.contact_impulse(self._surface_dofs, free.ravel()) + float(
            np.sum(vf * free))
        if held.any():
            work += self.ship.apply_impulse_at(self.surface_points(), held @ R.T)
        return work

    def applied_load(self) -> np.ndarray:
        """(3,) resultant (N, world) of the applied loads now (contact and the ship's inertial
        loads excluded)."""
        return self.ship.R @ self.dofmap.to_nodal(self._f_load).sum(axis=0)

    def energy_terms(self) -> dict[str, float]:
        """World work of the applied loads, damping loss, and the kinetic correction of the
        free nodes' world accelerations (J); no support work (module docstring)."""
        s = self.solver
        return {"load_work": self.load_work, "support_work": 0.0,
                "damping_dissipated": s.damping_dissipated,
                "kinetic_correction": -0.125 * s.last_dt ** 2 * self._maa}

    def frame_history(self) -> dict[str, float | np.ndarray]:
        """As :meth:`FrameStructure.frame_history`; ``drive_work`` is the work of the ship's
        inertial loads on the elastic motion (J), an exchange with the ship."""
        hist = super().frame_history()
        hist["drive_work"] = self.inertial_work
        return hist

    def checkpoint_state(self) -> dict[str, np.ndarray | float]:
        """The moving-frame structure's state plus the loads' work and impulse."""
        out = super().checkpoint_state()
        out.update(load_work=self.load_work, external_impulse=self._external_impulse.copy(),
                   f_load=self._f_load.copy(), p_elastic=self._p0.copy(), maa=self._maa)
        return out

    def restore_state(self, state: dict) -> None:
        """Restore a state from :meth:`checkpoint_state` exactly."""
        super().restore_state(state)
        self.load_work, self._maa = float(state["load_work"]), float(state["maa"])
        self._external_impulse = np.array(state["external_impulse"], dtype=np.float64)
        self._f_load = np.array(state["f_load"], dtype=np.float64)
        self._p0 = np.array(state["p_elastic"], dtype=np.float64)
        self._world_now()

    def describe(self) -> str:
        """As :meth:`ElasticStructure.describe`, with the ship it rides on."""
        base = super(FrameStructure, self).describe()
        return (f"{base}; attached to ship '{self.ship.name}' (stepped with it; the critical "
                "step is that of the ship and the structure together)")
