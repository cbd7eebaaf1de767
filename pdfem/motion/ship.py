"""A free-floating rigid ship hull: six-degree-of-freedom rigid-body dynamics under gravity,
hydrostatic pressure on its wetted surface, an optional thrust or surge speed, and the ice's
contact impulses (SI units: m, kg, s, N, N m, J; equations in docs/ship.md).

State: the centre of gravity ``c`` and its velocity ``v``, the attitude as a unit quaternion
``q`` (body -> world, identity for the mesh as given) and the angular momentum ``L`` in world
axes. The body-axes inertia is ``I_b = m diag(k_x^2, k_y^2, k_z^2)`` (radii of gyration about
the centre of gravity), the angular velocity ``w = R I_b^-1 R^T L``. One step of ``h`` is
velocity Verlet for the translation and the angular momentum with an exact rotation update::

    v += h/2 F / m,  L += h/2 M;   c += h v;   q <- exp(h w_mid) q   (unit quaternions)
    F, M at the new pose;           v += h/2 F / m,  L += h/2 M

with ``w_mid`` the angular velocity of ``L`` at the attitude rotated by ``h w / 2`` (a
midpoint predictor, so the rotation is second-order accurate like the translation).

``F = m g + F_hydrostatic + thrust R e_x`` and ``M`` the hydrostatic moment about ``c``
(:func:`pdfem.motion.hydrostatics.hydrostatics`: the pressure rho g (level - z) integrated over the
part of each triangle below the water surface, recomputed every step, not linearised). The ice
acts through :meth:`apply_surface_impulse` (a jump of ``v`` and ``L`` by the resultant impulse
and its moment about ``c``; its work, the kinetic-energy change, is booked by the coupler). For
the contact the hull counts as infinitely heavy at each node (:meth:`surface_inverse_mass` is
zero), fine for a ship thousands of times heavier than an ice particle.

Energy: the ship's kinetic energy ``m v^2 / 2 + L . w / 2`` and its potential energy in gravity
and the water, ``m |g| (z_G - level + H) + rho g int_V (level - z) dV`` (exact; the datum, H
the hull's height, makes it positive while any of the hull is above the keel's depth), are
stored energies of the balance (``structure_kinetic``, ``structure_potential``); the thrust's
work (trapezoid rule) is ``load_work`` and the work of holding a surge speed ``support_work``.
Not modelled: radiation damping, added mass and viscous forces of the hull, waves
(docs/ship.md).
"""

from __future__ import annotations


import numpy as np

from pdfem.errors import InputError
from pdfem.fem.base import Structure
from pdfem.geometry.vectors import cross
from pdfem.motion.hydrostatics import hydrostatics
from pdfem.motion.rigid import read_surface
from pdfem.fem.surface_patches import surface_patches
from pdfem.fem.surface import orient_outward
from pdfem.motion.rotation import (quaternion_matrix, quaternion_product, rotation_quaternion,
                                   rotation_vector)


class Ship(Structure):
    """A free rigid hull floating in still water (6 DOF; see the module docstring).

    Parameters
    ----------
    points, triangles
        The closed hull surface (m) as given in the mesh (the attitude there is the identity)
        and its triangles (outward oriented here).
    density, level, gravity
        Water density (kg/m^3), z of the still water surface (m), gravity vector (m/s^2,
        along -z).
    mass
        Mass (kg); ``None``: the displaced mass ``rho V`` of the hull as given.
    centre_of_gravity
        (3,) centre of gravity in the mesh as given (m); ``None``: above the centre of buoyancy
        of the hull as given, at the water surface.
    radii_of_gyration
        (3,) radii of gyration about the body x, y, z axes through the centre of gravity (m).
    initial_displacement, initial_rotation
        A rigid displacement (m) and rotation vector about the centre of gravity (rad) applied
        to the hull at t = 0 (to release it off equilibrium).
    initial_velocity, initial_angular_velocity
        (3,) m/s and rad/s at t = 0, world axes.
    thrust
        Constant force along the body x axis (N).
    surge_speed, ramp_time
        If ``surge_speed`` is not ``None``, the world x velocity of the centre of gravity is
        held at ``surge_speed min(1, t / ramp_time)`` (m/s, s).
    name
        Structure name.
    """

    prescribed_motion = False

    def __init__(self, points, triangles, *, density: float, level: float, gravity,
                 radii_of_gyration, mass: float | None = None, centre_of_gravity=None,
                 initial_displacement=(0.0, 0.0, 0.0), initial_rotation=(0.0, 0.0, 0.0),
                 initial_velocity=(0.0, 0.0, 0.0), initial_angular_velocity=(0.0, 0.0, 0.0),
                 thrust: float = 0.0, surge_speed: float | None = None, ramp_time: float = 0.0,
                 name: str = "ship") -> None:
        self.name = name
        self.patches: dict[str, np.ndarray] = {}
        self.x_mesh = np.ascontiguousarray(points, dtype=np.float64)
        self.surface_triangles = orient_outward(self.x_mesh, np.asarray(triangles, np.int64))
        self.density, self.level = float(density), float(level)
        self.gravity = np.asarray(gravity, dtype=np.float64).reshape(3)
        self.g = float(np.linalg.norm(self.gravity))
        given = hydrostatics(self.x_mesh, self.surface_triangles, self.level, self.density,
                             self.g, np.zeros(3))
        if given.volume <= 0.0:
            raise ValueError(f"ship '{name}': no part of the hull is below the water surface "
                             f"z = {self.level:g} m")
        self.mass = self.density * given.volume if mass is None else float(mass)
        b = given.centre_of_buoyancy
        cg = (b[0], b[1], self.level) if centre_of_gravity is None else centre_of_gravity
        cg = np.asarray(cg, dtype=np.float64).reshape(3)
        k = np.asarray(radii_of_gyration, dtype=np.float64).reshape(3)
        self.inertia = self.mass * k * k                       # body axes, kg m^2
        self.body_points = self.x_mesh - cg                    # body-frame coordinates, m
        self.cg_mesh = cg                                      # G in the mesh as given, m
        self.q = rotation_quaternion(initial_rotation)
        self.c = cg + np.asarray(initial_displacement, dtype=np.float64).reshape(3)
        self.x0 = self.c + self.body_points @ quaternion_matrix(self.q).T
        self.v = np.asarray(initial_velocity, dtype=np.float64).reshape(3).copy()
        R = quaternion_matrix(self.q)
        w0 = np.asarray(initial_angular_velocity, dtype=np.float64).reshape(3)
        self.L = R @ (self.inertia * (R.T @ w0))
        self.thrust, self.surge_speed, self.ramp_time = float(thrust), surge_speed, ramp_time
        self.time = 0.0
        self.thrust_work = self.surge_work = 0.0
        # structures riding on the hull (pdfem.motion.attached_frame): their support impulses (N s,
        # world, summed) and work (J); the mean accelerations of the last step (m/s^2, rad/s^2)
        self.attached_impulse, self.attached_work = np.zeros(3), 0.0
        self.external_impulse = np.zeros(3)   # N s: gravity, water, thrust, held surge
        self.acceleration, self.angular_acceleration = np.zeros(3), np.zeros(3)
        self._surface_forces = np.zeros((len(self.x_mesh), 3))
        height = float(np.ptp(self.x_mesh[:, 2]))
        self.datum = np.array([0.0, 0.0, self.level - height])  # m, potential datum
        self._update()
        self._v_prev, self._w_prev = self.v.copy(), self.omega.copy()

    @classmethod
    def from_msh(cls, path, group: str = "contact", **kwargs) -> "Ship":
        """Build from a closed surface group of a gmsh file; ``kwargs`` as the constructor's."""
        pts, tri = read_surface(path, group)
        ship = cls(pts, tri, **kwargs)
        ship.patches = surface_patches(path, group, ship.x_mesh, ship.surface_triangles)
        return ship

    @classmethod
    def from_case(cls, cfg, path, file: str = "<case>") -> "Ship":
        """The ship of a case's ``kind = "ship"`` structure (a
        :class:`~pdfem.case.config.StructureConfig` with its ``ship``), from its contact group.

        Raises
        ------
        InputError
            If the case has no ``[water]`` section.
        """
        ship = cfg.ship
        if ship.water_density is None:
            raise InputError(file, f"{cfg.field}.kind", "a ship floats: the case needs a [water] "
                             "section (density, level) for its hydrostatics", cfg.kind)
        s = ship.section
        pts, tri = read_surface(path, cfg.contact_group)
        k = s.radii_of_gyration
        if k is None:
            wet = pts[pts[:, 2] <= ship.water_level]
            span = np.ptp(wet if len(wet) else pts, axis=0)
            k = (0.4 * span[1], 0.25 * span[0], 0.25 * span[0])
        body = cls(pts, tri, density=ship.water_density, level=ship.water_level,
                   gravity=ship.gravity, radii_of_gyration=k, mass=s.mass,
                   centre_of_gravity=s.center_of_gravity,
                   initial_displacement=s.initial_displacement,
                   initial_rotation=s.initial_rotation, initial_velocity=s.initial_velocity,
                   initial_angular_velocity=s.initial_angular_velocity, thrust=s.thrust,
                   surge_speed=s.surge_speed, ramp_time=s.ramp_time, name=cfg.name)
        body.patches = surface_patches(path, cfg.contact_group, body.x_mesh,
                                       body.surface_triangles)
        return body

    # ------------------------------------------------------------------ dynamics
    def _update(self) -> None:
        """Pose, surface velocities and loads at the current state."""
        self.R = quaternion_matrix(self.q)
        self._x = self.c + self.body_points @ self.R.T
        self.omega = self.R @ ((self.R.T @ self.L) / self.inertia)
        self._v = self.v + cross(self.omega, self._x - self.c)
        self.hydro = hydrostatics(self._x, self.surface_triangles, self.level, self.density,
                                  self.g, self.c)
        self.thrust_force = self.thrust * self.R[:, 0]
        self.force = self.mass * self.gravity + self.hydro.force + self.thrust_force
        self.moment = self.hydro.moment

    def step(self, dt: float) -> None:
        """Advance by ``dt`` (s): velocity Verlet with an exact rotation update."""
        h = float(dt)
        thrust0, force0 = self.thrust_force, self.force
        self.v += 0.5 * h * self.force / self.mass
        self.L += 0.5 * h * self.moment
        c_old = self.c.copy()
        omega = self.R @ ((self.R.T @ self.L) / self.inertia)
        half = quaternion_matrix(quaternion_product(rotation_quaternion(0.5 * h * omega), self.q))
        omega = half @ ((half.T @ self.L) / self.inertia)   # at mid-step: second order
        self.c = self.c + h * self.v
        q = quaternion_product(rotation_quaternion(h * omega), self.q)
        self.q = q / np.linalg.norm(q)
        self._update()
        self.v += 0.5 * h * self.force / self.mass
        self.L += 0.5 * h * self.moment
        self.thrust_work += float(0.5 * (thrust0 + self.thrust_force) @ (self.c - c_old))
        self.external_impulse += 0.5 * h * (force0 + self.force)
        self.time += h
        self._update_velocity()
        self._hold_surge()
        self.acceleration = (self.v - self._v_prev) / h
        self.angular_acceleration = (self.omega - self._w_prev) / h
        self._v_prev, self._w_prev = self.v.copy(), self.omega.copy()

    def _hold_surge(self) -> None:
        """Hold the surge speed (if given); book the work of holding it."""
        if self.surge_speed is None:
            return
        ramp = 1.0 if self.ramp_time <= 0.0 else min(1.0, self.time / self.ramp_time)
        target = self.surge_speed * ramp
        self.surge_work += 0.5 * self.mass * (target * target - self.v[0] * self.v[0])
        self.external_impulse[0] += self.mass * (target - self.v[0])
        self.v[0] = target
        self._update_velocity()

    def apply_surface_impulse(self, impulse: np.ndarray) -> float:
        """Jump of ``v`` and ``L`` by the resultant impulse (N s) and its moment about ``c``;
        returns their work, the kinetic-energy change (J)."""
        j = np.asarray(impulse, dtype=np.float64)
        before = self.kinetic_energy()
        self.v += j.sum(axis=0) / self.mass
        self.L += cross(self._x - self.c, j).sum(axis=0)
        self._update_velocity()
        work = self.kinetic_energy() - before
        self._hold_surge()
        return work

    def apply_attached_impulse(self, points: np.ndarray, impulse: np.ndarray) -> None:
        """The impulses (N s, (N, 3), world) that a structure riding on the hull passes on
        through its supports at ``points`` (m): a jump of ``v`` and ``L`` as for the ice's;
        their work (J, the kinetic-energy change) is booked in ``support_work``."""
        j = np.asarray(impulse, dtype=np.float64).reshape(-1, 3)
        before = self.kinetic_energy()
        self.v += j.sum(axis=0) / self.mass
        self.L += cross(np.asarray(points, dtype=np.float64) - self.c, j).sum(axis=0)
        self._update_velocity()
        self.attached_impulse += j.sum(axis=0)
        self.attached_work += self.kinetic_energy() - before
        self._hold_surge()

    def _update_velocity(self) -> None:
        """Angular velocity and surface velocities after a change of ``v`` or ``L``."""
        self.omega = self.R @ ((self.R.T @ self.L) / self.inertia)
        self._v = self.v + cross(self.omega, self._x - self.c)

    # ------------------------------------------------------------------ energies
    def kinetic_energy(self) -> float:
        """``m v^2 / 2 + L . w / 2`` (J)."""
        return 0.5 * self.mass * float(self.v @ self.v) + 0.5 * float(self.L @ self.omega)

    def potential_energy(self) -> float:
        """Gravity and hydrostatic potential (J): ``-m g . (c - c_datum) + rho g int_V (level - z)
        dV`` with ``c_datum`` the hull's height H below the water surface."""
        return (-self.mass * float(self.gravity @ (self.c - self.datum))
                + self.hydro.potential)

    def energy_terms(self) -> dict[str, float]:
        """``load_work``: work of the thrust (J); ``support_work``: of holding the surge
        speed."""
        return {"load_work": self.thrust_work,
                "support_work": self.surge_work + self.attached_work, "damping_dissipated": 0.0,
                "kinetic_correction": 0.0}

    def applied_load(self) -> np.ndarray:
        """(3,) gravity + hydrostatic force + thrust now (N)."""
        return self.force.copy()

    # ------------------------------------------------------------------ output
    def motion_history(self) -> dict[str, np.ndarray | float]:
        """One row every coupling step: ``position`` of the centre of gravity (m),
        ``rotation`` vector (rad, from the hull as given), ``velocity`` (m/s),
        ``angular_velocity`` (rad/s, world axes), ``hydrostatic_force`` (N),
        ``hydrostatic_moment`` (N m, about the centre of gravity); ``attached_impulse`` (N s)
        and ``attached_work`` (J) handed over by structures riding on the hull so far,
        ``external_impulse`` (N s) of gravity, water, thrust and held surge so far."""
        return {"position": self.c.copy(), "rotation": rotation_vector(self.q),
                "velocity": self.v.copy(), "angular_velocity": self.omega.copy(),
                "hydrostatic_force": self.hydro.force.copy(),
                "hydrostatic_moment": self.hydro.moment.copy(),
                "attached_impulse": self.attached_impulse.copy(),
                "attached_work": self.attached_work,
                "external_impulse": self.external_impulse.copy()}

    def output_mesh(self) -> tuple[np.ndarray, np.ndarray, str]:
        """Hull nodes at t = 0 (m) and triangles."""
        return self.x0, self.surface_triangles, "triangle"

    def output_fields(self) -> dict[str, np.ndarray]:
        """``u`` displacement (m) and ``v`` velocity (m/s) of the hull nodes."""
        return {"u": self._x - self.x0, "v": self._v.copy()}

    def surface_groups(self) -> dict[str, np.ndarray]:
        """The load patches: the hull mesh's other groups (bow, shoulder, midship, stern,
        bow_panel) on the contact surface (:mod:`pdfem.fem.surface_patches`)."""
        return self.patches

    def describe(self) -> str:
        """Mass, displacement, inertia."""
        return (f"ship '{self.name}': {len(self.x_mesh):,} hull nodes, mass {self.mass:.4g} kg, "
                f"displacement at start {self.density * self.hydro.volume:.4g} kg, "
                f"I = {np.array2string(self.inertia, precision=4)} kg m^2")

    def is_finite(self) -> bool:
        """Whether the state is finite."""
        return bool(np.isfinite(self.c).all() and np.isfinite(self.v).all()
                    and np.isfinite(self.L).all() and np.isfinite(self.q).all())

    def surface_points(self) -> np.ndarray:
        """(Ns, 3) hull node positions (m)."""
        return self._x.copy()

    def surface_velocities(self) -> np.ndarray:
        """(Ns, 3) hull node velocities ``v + w x (x - c)`` (m/s)."""
        return self._v.copy()

    def surface_rotation(self) -> np.ndarray:
        """(3, 3) the hull's attitude ``R`` (body to world): the hull is rigid."""
        return self.R.copy()

    # ------------------------------------------------------------------ checkpoints
    def checkpoint_state(self) -> dict[str, np.ndarray | float]:
        """c, q, v, L, time and the work counters."""
        return {"c": self.c.copy(), "q": self.q.copy(), "v": self.v.copy(), "L": self.L.copy(),
                "time": self.time, "thrust_work": self.thrust_work,
                "surge_work": self.surge_work, "surface_forces": self._surface_forces.copy(),
                "attached": np.concatenate([self.attached_impulse, self.external_impulse,
                                            self._v_prev, self._w_prev, self.acceleration,
                                            self.angular_acceleration, [self.attached_work]])}

    def restore_state(self, state: dict) -> None:
        """Restore a state from :meth:`checkpoint_state` exactly."""
        for key in ("c", "v", "L"):
            setattr(self, key, np.array(state[key], dtype=np.float64).reshape(3))
        self.q = np.array(state["q"], dtype=np.float64).reshape(4)
        self.time = float(state["time"])
        self.thrust_work, self.surge_work = float(state["thrust_work"]), float(state["surge_work"])
        self._surface_forces[:] = state["surface_forces"]
        self._update()
        a = np.array(state["attached"], dtype=np.float64)
        (self.attached_impulse, self.external_impulse, self._v_prev, self._w_prev,
         self.acceleration, self.angular_acceleration) = (a[k:k + 3].copy() for k in range(0, 18, 3))
        self.attached_work = float(a[18])
