"""An elastic structure carried by a moving (rotating, translating) frame: a spinning propeller
blade or bar (docs/rotating_structures.md).

:class:`FrameStructure` is an :class:`pdfem.fem.structure.ElasticStructure` whose displacement
DOFs are the elastic displacement u_e relative to a :class:`pdfem.motion.moving_frame.MovingFrame`,
in frame axes. Each step adds the frame's inertial loads (centrifugal on r = X - c0 + u_e, so
with spin softening; Coriolis; Euler and translation during the ramp) and the stress
stiffening of the centrifugal prestress (-s^2 K_sigma u_e) to the applied loads,
evaluated with the state at the start of the step (explicit, like the rest of the scheme).
Supports hold their nodes fixed in the frame; Rayleigh damping acts on u_e' only. The contact
code sees the true surface x = c + R (X - c0 + u_e) and its true velocity; contact forces and
impulses (world axes) are turned into frame axes (R^T F).

Energy (frame axes): the kinetic energy reported is that of the elastic motion, 1/2 u_e'.M u_e'.
The drive holds the frame's motion whatever the loads, so the work it does on the elastic
motion is part of ``support_work``: the work of the inertial loads (trapezoid rule, as the
integrator counts every force) minus the work of the contact impulses on the frame's own
velocity (the drive absorbs it). With it the structure's balance closes to round-off.
When the frame turns, ``shaft`` (:class:`pdfem.motion.shaft_loads.ShaftLoads`) records the contact
impulses and the shaft's torque every step (shaft torque, thrust, blade loads).

Implicit steps (``integrator = "implicit"``, :mod:`pdfem.fem.implicit`). The inertial loads
stay explicit, evaluated on the state at the step's start, so the Newmark step remains the
linear, factorised ``A = M + dt/2 C + dt^2/4 K`` of the structure at rest (no Coriolis or
softening matrix in it). At the milling case's coupling step (omega dt = 4e-4) this explicit
part is far inside its stability limit 2: the largest term, the stress stiffening
``s^2 K_sigma``, has ``omega_sigma dt = 0.20`` (the largest eigenvalue of ``M^-1 K_sigma`` at
full speed; K's highest mode has ``omega dt = 108``), and Coriolis, Euler and softening are of
order ``omega dt``. The contact impulses amend the step just taken
(:meth:`pdfem.fem.implicit.Newmark.end_impulse`) as a force at its end, in frame axes turned by
the rotation at the step's end, ``R(t + dt)^T J``; so the surface's compliance for the contact
is the frame-axes blocks of ``A^-1 / 2`` turned into world axes the same way,
``R(t + dt) C R(t + dt)^T`` per node (:meth:`FrameStructure.surface_compliance`; the contact
resolves a step's impulses against the surface at the step's end). Their work in the world is
``J . (x_end - x_start) / dt``, the surface's true displacement over the step: the elastic part
``R^T J . (u_e,end - u_e,start) / dt`` (the integrator's, exact), and the drive's part
``J . (c(t + dt) + R(t + dt) r - c(t) - R(t) r) / dt`` (``r`` the node's position in the frame
at the step's start), which the drive absorbs as with explicit steps.
SI units throughout.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from pdfem.fem.central_difference_kernels import trapezoid_work
from pdfem.fem.node_blocks import NodeBlockOperator
from pdfem.fem.static import static_displacement
from pdfem.fem.structure import ElasticStructure
from pdfem.motion.frame_kernels import inertial_loads, surface_world
from pdfem.motion.moving_frame import MovingFrame
from pdfem.motion.shaft_loads import ShaftLoads
from pdfem.motion.stress_stiffening import centrifugal_stiffness
from pdfem.parallel.comm import SerialComm


_NONE = np.zeros(0)
"""No geometric stiffness force (:func:`pdfem.motion.frame_kernels.inertial_loads`)."""


class FrameStructure(ElasticStructure):
    """An elastic structure solved relative to a moving frame.

    Parameters
    ----------
    *args, **kwargs
        As for :class:`pdfem.fem.structure.ElasticStructure`.
    frame
        The frame's motion (rotation about a fixed axis through its centre, translation, ramp).
    stress_stiffening
        Add the geometric stiffness of the centrifugal prestress, s(t)^2 K_sigma
        (:mod:`pdfem.motion.stress_stiffening`); default True.
    """

    def __init__(self, *args, frame: MovingFrame, stress_stiffening: bool = True, **kwargs):
        super().__init__(*args, **kwargs)
        self.frame = frame
        self._r0 = self.node_points - np.asarray(frame.center, dtype=np.float64)
        self._dofs = np.ascontiguousarray(self.dofmap.nodal_dofs)         # (3, Nn)
        self._surface_r0 = np.ascontiguousarray(self._r0[self.surface_nodes])
        self._surface_table = np.ascontiguousarray(self._surface_dofs.reshape(-1, 3))
        self.node_mass = self.dofmap.to_nodal(self.solver.m)[:, 0].copy()
        self.K_sigma = (centrifugal_stiffness(self, frame, self._r0, self.node_mass)
                        if stress_stiffening and np.any(frame.angular_velocity) else None)
        if self.K_sigma is not None:   # K_sigma u with every K u (one pass over the blocks)
            self.solver.add_companion(NodeBlockOperator(self.K_sigma))
        self.inertial_work = 0.0     # J, work of the inertial loads on u_e
        self._step_start = None      # implicit: the step's t, surface r, u_e, inertial loads, work
        self._turned = (None, None)  # implicit: (time, the compliance turned to world axes)
        self.drive_impulse_work = 0.0  # J, work of contact impulses on the frame's velocity
        self._f_inertial = self._inertial_dofs(0.0)
        self.solver.initialize(f_ext=self.external_force_dofs(0.0) + self._f_inertial)
        self.shaft = None
        self.starts_steady = bool(np.any(frame.angular_velocity)
                                  and frame.speed_factor(0.0)[0] > 0.0)
        if self.starts_steady:
            # turning at full speed from t = 0 (no ramp): start in the steady state
            self.set_state(displacement=self.steady_displacement())
        self._comm = SerialComm()
        self.shaft = ShaftLoads(self) if np.any(frame.angular_velocity) else None

    def distribute(self, comm) -> None:
        """As :meth:`pdfem.fem.structure.ElasticStructure.distribute`, and the shaft's blade
        stresses (:meth:`pdfem.motion.shaft_loads.ShaftLoads.distribute`)."""
        super().distribute(comm)
        self._comm = comm
        if self.shaft is not None:
            self.shaft.distribute(comm)

    def add_surface_load(self, group: str, traction=(0.0, 0.0, 0.0), pressure: float = 0.0,
                         history=None) -> None:
        """As :meth:`pdfem.fem.loads.AppliedLoads.add_surface_load`; a structure that starts in
        steady rotation (:meth:`steady_displacement`) and has not stepped yet starts in the
        steady state with the load (its value at t = 0), not without it: the load does not set
        off a ringing of its own, and the shaft's sums start there."""
        super().add_surface_load(group, traction, pressure, history)
        if self.starts_steady and self.solver.time == 0.0:
            self.set_state(displacement=self.steady_displacement())
            if self.shaft is not None:
                self.shaft = ShaftLoads(self, self._comm)

    # ------------------------------------------------------------------ frame kinematics
    def relative_motion(self) -> tuple[np.ndarray, np.ndarray]:
        """(Nn, 3) r = X - c0 + u_e (m) and u_e' (m/s), frame axes."""
        return (self._r0 + self.dofmap.to_nodal(self.solver.u),
                self.dofmap.to_nodal(self.solver.v))

    def _inertial_dofs(self, t: float, u: np.ndarray | None = None,
                       v: np.ndarray | None = None) -> np.ndarray:
        """Inertial loads (N, DOF vector, frame axes) at time ``t`` (s) on the current state,
        or on the displacement ``u`` (m) and velocity ``v`` (m/s) given."""
        f = np.empty(self.dofmap.n_dofs)
        ksu = _NONE if self.K_sigma is None else self.solver.companion_force()
        inertial_loads(self._r0, self.solver.u if u is None else u,
                       self.solver.v if v is None else v, self._dofs, self.node_mass,
                       *self.frame.inertial_rates(t), self.frame.speed_factor(t)[0] ** 2, ksu, f)
        return f

    def steady_displacement(self) -> np.ndarray:
        """(Nn, 3) the elastic displacement (m, frame axes) in which the structure turns
        steadily with the frame at t = 0: the static equilibrium of the stiffness with the
        loads at t = 0 and the inertial loads of the steady rotation, the centrifugal load and
        the prestress's geometric stiffness taken on the displaced nodes,
        ``(K + s^2 K_sigma - spin softening) u = f_ext + f_inertial`` on the free DOFs
        (:meth:`rotating_stiffness`, :func:`pdfem.fem.static.static_displacement`), the held
        DOFs at their values now. In it the relative velocity and acceleration are zero: a
        structure that starts turning at full speed (``ramp_time`` 0) starts there, without the
        ringing of a sudden spin-up.

        Raises
        ------
        ValueError
            If the supports leave the spinning structure free to move (a singular stiffness).
        """
        u0 = self.solver.u
        held = ~self.solver.free
        k_rot = self.rotating_stiffness(0.0)
        # f_inertial(u) = f_inertial(u0) - (k_rot - K)(u - u0); the held DOFs' part moved over
        force = (self.external_force_dofs(0.0) + self._inertial_dofs(0.0)
                 + (k_rot - sp.csr_matrix(self.K)) @ u0 - k_rot[:, held] @ u0[held])
        u = self.dofmap.to_dofs(static_displacement(self, force, k_rot))
        u[held] = u0[held]
        return self.dofmap.to_nodal(u)

    def rotating_stiffness(self, t: float | None = None) -> sp.csr_matrix:
        """K + s^2 K_sigma - spin softening (N/m, DOF order) at time ``t`` (s; default now):
        the stiffness of small motions about the spinning state, without Coriolis
        (for the frequencies of the spinning structure, e.g. flapwise bending)."""
        f = self.frame.state(self.solver.time if t is None else t)
        w = f["w"]
        soft = self.node_mass[:, None, None] * (np.dot(w, w) * np.eye(3) - np.outer(w, w))
        n = self.n_nodes
        rows = self.dofmap.nodal_dofs.T                  # (Nn, 3) DOF of (node, component)
        ii = np.repeat(rows, 3, axis=1).ravel()
        jj = np.tile(rows, (1, 3)).ravel()
        k = sp.csr_matrix(self.K) - sp.csr_matrix((soft.reshape(n, 9).ravel(), (ii, jj)),
                                                  shape=self.K.shape)
        if self.K_sigma is not None:
            k = k + self.frame.speed_factor(self.solver.time if t is None else t)[0] ** 2 \
                * self.K_sigma
        return sp.csr_matrix(k)

    def rotation(self) -> np.ndarray:
        """(3, 3) rotation R of the frame now (frame axes -> world axes)."""
        return self.frame.state(self.solver.time)["R"]

    def step(self, dt: float) -> None:
        """Advance by ``dt`` (s) with the applied, contact and inertial loads (the inertial
        ones at ``t + dt`` on the state at ``t``)."""
        t_new = self.solver.time + dt
        jump = self.frame.velocity_jump(self.solver.time, t_new)
        if jump.any():  # a kink of the frame's path: the nodes keep their world velocity
            before = self.kinetic_energy()
            dv = np.broadcast_to(-(self.rotation().T @ jump), (self.n_nodes, 3))
            self.solver.apply_impulse(np.arange(self.dofmap.n_dofs),
                                      self.solver.m * self.dofmap.to_dofs(dv))
            self.drive_impulse_work -= self.kinetic_energy() - before  # the drive's work
        f_in = self._inertial_dofs(t_new)
        u_old = self.solver.u
        if self.implicit:   # what the contact impulses that amend this step need
            self._step_start = (self.solver.time, self._surface_relative(), u_old,
                                self._f_inertial, self.inertial_work, f_in)
        self.solver.step(dt, self.external_force_dofs(t_new) + f_in)
        self.inertial_work += trapezoid_work(self._f_inertial, f_in, self.solver.u, u_old)
        self._f_inertial = f_in
        if self.shaft is not None:
            self.shaft.after_step(dt)

    def set_state(self, displacement: np.ndarray | None = None,
                  velocity: np.ndarray | None = None) -> None:
        """Set the elastic displacement (m) and velocity (m/s) relative to the frame (frame
        axes, (Nn, 3)) and recompute the acceleration with the inertial loads."""
        super().set_state(displacement, velocity)
        self._f_inertial = self._inertial_dofs(self.solver.time)
        self.solver.initialize(self.solver.u, self.solver.v,
                               self.external_force_dofs() + self._f_inertial, self.solver.time)
        if self.shaft is not None:
            self.shaft.shaft_torque, self.shaft.shaft_power = self.shaft.support_torque_power()

    # ------------------------------------------------------------------ contact interface
    def surface_points(self) -> np.ndarray:
        """(Ns, 3) true positions (m, world) of the contact-surface nodes."""
        return self.surface_state()[0]

    def surface_velocities(self) -> np.ndarray:
        """(Ns, 3) true velocities (m/s, world) of the contact-surface nodes."""
        return self.surface_state()[1]

    def surface_state(self) -> tuple[np.ndarray, np.ndarray]:
        """(Ns, 3) true positions (m) and velocities (m/s) of the surface nodes, world axes,
        in one pass (:func:`pdfem.motion.frame_kernels.surface_world`)."""
        f = self.frame.state(self.solver.time)
        x, v = np.empty_like(self._surface_r0), np.empty_like(self._surface_r0)
        surface_world(self._surface_r0, self.solver.u, self.solver.v, self._surface_table,
                      f["R"], f["c"], f["c_dot"], f["w"], x, v)
        return x, v

    def _surface_relative(self) -> np.ndarray:
        """(Ns, 3) r = X - c0 + u_e (m, frame axes) of the surface nodes."""
        return self._surface_r0 + self.solver.u[self._surface_table]

    def set_surface_forces(self, forces: np.ndarray) -> None:
        """Contact forces (N, (Ns, 3), world axes), turned into frame axes (R^T F)."""
        super().set_surface_forces(np.asarray(forces, dtype=np.float64) @ self.rotation())

    def surface_compliance(self):
        """Explicit: as :meth:`ElasticStructure.surface_compliance`. Implicit: its frame-axes
        blocks with the rotation now (the step's end), which turns the response to the
        contacts into world axes, ``R S R^T`` (module docstring)."""
        c = super().surface_compliance()
        if not self.implicit:
            return c
        t = self.solver.time
        if self._turned[0] != t:
            self._turned = (t, c.turned(self.rotation()))
        return self._turned[1]

    def apply_surface_impulse(self, impulse: np.ndarray) -> float:
        """Explicit: impulses (N s, (Ns, 3), world axes) as a jump of u_e' (R^T J); returns
        their work (J) in the world, ``v . J + J^2 / (2 m)`` with the true velocity ``v`` (on
        supports, which move with the frame, ``v_frame . J``); the part ``v_frame . J`` goes to
        the drive (``support_work``). Implicit: the impulses amend the step just taken
        (:meth:`_amend_step`)."""
        j = np.asarray(impulse, dtype=np.float64).reshape(-1, 3)
        if self.implicit:
            return self._amend_step(j)
        r = self._surface_relative()
        vf = self.frame.frame_velocity(self.solver.time, r)
        drive = float(np.sum(vf * j))   # supports too: the frame carries them into the ice
        work = super().apply_surface_impulse(j @ self.rotation())
        self.drive_impulse_work += drive
        if self.shaft is not None:
            self.shaft.add_impulse(j, self.rotation(), r, work + drive)
        return work + drive

    def _amend_step(self, j: np.ndarray) -> float:
        """Impulses ``j`` (N s, (Ns, 3), world axes) on the implicit step just taken, as a force
        at its end in frame axes, ``R^T J`` (:meth:`pdfem.fem.implicit.Newmark.end_impulse`);
        the inertial loads' work over the step and the shaft's torque at its end are taken
        again with the amended state. Returns their work in the world (J): the elastic part
        and the drive's, ``J . (frame motion of the surface points over the step) / dt``
        (module docstring), which goes to the drive (``support_work``)."""
        t0, r0, u_old, f_old, work_old, f_in = self._step_start
        rot = self.rotation()
        work = super().apply_surface_impulse(j @ rot)
        self.inertial_work = work_old + trapezoid_work(f_old, f_in, self.solver.u, u_old)
        f0, f1 = self.frame.state(t0), self.frame.state(self.solver.time)
        moved = (f1["c"] - f0["c"]) + r0 @ (f1["R"] - f0["R"]).T
        drive = float(np.sum(j * moved)) / self.solver.last_dt
        self.drive_impulse_work += drive
        if self.shaft is not None:
            self.shaft.add_impulse(j, rot, self._surface_relative(), work + drive)
            self.shaft.amend_step()
        return work + drive

    # ------------------------------------------------------------------ results
    def total_displacement(self) -> np.ndarray:
        """(Nn, 3) displacement (m, world) from the reference configuration, x - X: the
        frame's motion plus the elastic part."""
        r, v = self.relative_motion()
        x, _ = self.frame.to_world(self.solver.time, r, v)
        return x - self.node_points

    def output_fields(self) -> dict[str, np.ndarray]:
        """``u`` (Nn, 3) total displacement x - X (m, world), ``u_elastic`` (m, frame axes),
        ``v`` true velocity (m/s, world), ``von_mises`` (Ne,) Pa from u_elastic."""
        r, v = self.relative_motion()
        x, w = self.frame.to_world(self.solver.time, r, v)
        return {"u": x - self.node_points, "u_elastic": self.displacement(), "v": w,
                "von_mises": self.von_mises()}

    def frame_history(self) -> dict[str, float | np.ndarray]:
        """As :meth:`ElasticStructure.frame_history` (energies of the elastic motion, reactions
        in frame axes), plus ``frame_angle`` (rad) and ``drive_work`` (J, the drive's work on
        the elastic motion, part of ``support_work``)."""
        hist = super().frame_history()
        hist["frame_angle"] = self.frame.angle(self.solver.time)
        hist["drive_work"] = self.inertial_work - self.drive_impulse_work
        return hist

    def energy_terms(self) -> dict[str, float]:
        """As :meth:`ElasticStructure.energy_terms`, with the drive's work on the elastic
        motion (inertial loads, less the impulses' work on the frame's velocity) in
        ``support_work`` and out of ``load_work`` (J)."""
        terms = super().energy_terms()
        terms["load_work"] -= self.inertial_work
        terms["support_work"] += self.inertial_work - self.drive_impulse_work
        return terms

    def checkpoint_state(self) -> dict[str, np.ndarray | float]:
        """The elastic structure's state plus the frame's inertial loads and works."""
        out = super().checkpoint_state()
        out.update(f_inertial=self._f_inertial.copy(), inertial_work=self.inertial_work,
                   drive_impulse_work=self.drive_impulse_work,
                   **(self.shaft.checkpoint_state() if self.shaft is not None else {}))
        return out

    def restore_state(self, state: dict) -> None:
        """Restore a state from :meth:`checkpoint_state` exactly."""
        super().restore_state(state)
        self._f_inertial = np.array(state["f_inertial"], dtype=np.float64)
        self.inertial_work = float(state["inertial_work"])
        self.drive_impulse_work = float(state["drive_impulse_work"])
        if self.shaft is not None:
            self.shaft.restore_state(state)

    def describe(self) -> str:
        """As :meth:`ElasticStructure.describe`, with the frame's motion."""
        f = self.frame
        return (f"{super().describe()}; moving frame: angular velocity {list(f.angular_velocity)} "
                f"rad/s about {list(f.center)} m, velocity {list(f.velocity)} m/s, ramp "
                f"{f.ramp_time:g} s")
