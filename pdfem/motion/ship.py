"""A free-floating rigid ship hull: six-degree-of-freedom rigid-body dynamics under gravity,
hydrostatic pressure on its wetted surface, an optional thrust or surge speed, the ice's
contact impulses and the elastic structures riding on it (SI units: m, kg, s, N, N m, J;
equations in docs/ship.md).

State: the centre of gravity ``c`` (G), the attitude as a unit quaternion ``q`` (body ->
world, identity for the mesh as given), and the momenta of the rigid body the ship integrates,
its linear momentum ``p`` and its angular momentum ``L`` about G, world axes. That body is the
hull with the supported degrees of freedom of the structures riding on it
(:mod:`pdfem.motion.attached_frame`); its mass matrix ``M_B`` (6 x 6, body axes, about G) is
the whole ship's, ``diag(m, m, m, m k_x^2, m k_y^2, m k_z^2)`` (mass and radii of gyration
about G), less the free degrees of freedom of the riders (:mod:`pdfem.motion.rigid_inertia`):
without riders, the whole ship. Its velocities ``nu_b = (v_b, w_b) = M_B^-1 (R^T p, R^T L)``.
One step of ``h`` is velocity Verlet for the momenta with an exact rotation update::

    p += h/2 F,  L += h/2 M;          F, M: loads on the body, M about G
    c += h v_mid,  q <- exp(h w_mid) q,  L -= (c_new - c) x p   (L about the moving G)
    F, M at the new pose;  p += h/2 F,  L += h/2 M

with ``(v_mid, w_mid)`` the velocities at the attitude turned by ``h w / 2`` and G moved by
``h v / 2`` (a midpoint predictor: second order like the translation). Without riders
``v = p / m`` and the step is that of a rigid body about its centre of gravity.

``F = m g + F_hydrostatic + thrust R e_x`` (+ the riders' support loads) and ``M`` the moment
about G (:func:`pdfem.motion.hydrostatics.hydrostatics`: the pressure rho g (level - z)
integrated over the part of each triangle below the water surface, recomputed every step, not
linearised). The ice acts through :meth:`apply_surface_impulse` (a jump of ``p`` and ``L`` by
the resultant impulse and its moment about G; its work, the kinetic-energy change, is booked
by the coupler). For the contact the hull counts as infinitely heavy at each node
(:meth:`surface_inverse_mass` is zero), fine for a ship thousands of times heavier than an ice
particle.

Riders (:meth:`attach`): in each step the ship takes its half kick and its drift, then each
rider the first half of its step (its half kick and drift, relative to the ship) and hands the
ship the loads its free degrees of freedom put on the supported ones (:meth:`step`); with them
the ship takes its second half kick and gives the riders its accelerations at the step's end
(:attr:`rates`), with which they end their step. The two half kicks of each side use the same
accelerations at the same instant, so the pair is velocity Verlet on the whole ship, stable at
the riders' own step for any share of the mass they carry (docs/ship.md). A jump of the
ship's velocity (an impulse, the held surge speed) leaves the riders' free nodes their world
velocity.

Energy: the kinetic energy of the integrated body ``nu . M_B nu / 2`` (the riders book their
free nodes' own) and the ship's potential energy in gravity and the water,
``m |g| (z_G - level + H) + rho g int_V (level - z) dV`` (exact; the datum, H the hull's
height, makes it positive while any of the hull is above the keel's depth), are stored
energies of the balance (``structure_kinetic``, ``structure_potential``), with the scheme's
``kinetic_correction`` ``-(h^2/8) a . M_B a`` (the acceleration of the loads, as for the
central differences of :mod:`pdfem.fem.explicit`); the thrust's work (trapezoid rule) is
``load_work`` and the work of holding a surge speed ``support_work``. The weight of the whole
ship acts at G (the riders' elastic motion feels no gravity, as for any elastic structure).
Not modelled: radiation damping, added mass and viscous forces of the hull, waves
(docs/ship.md).
"""

from __future__ import annotations


import numpy as np

from pdfem.errors import InputError
from pdfem.fem.base import Structure
from pdfem.geometry.vectors import cross
from pdfem.motion.attached_step import assembly_max_eigenvalue, hull_inertia_problem
from pdfem.motion.hydrostatics import hydrostatics, restoring_stiffness
from pdfem.motion.rigid import read_surface
from pdfem.motion.rigid_inertia import ship_inertia
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
        Mass (kg) of the whole ship, the structures riding on it included; ``None``: the
        displaced mass ``rho V`` of the hull as given.
    centre_of_gravity
        (3,) centre of gravity of the whole ship in the mesh as given (m); ``None``: above the
        centre of buoyancy of the hull as given, at the water surface.
    radii_of_gyration
        (3,) radii of gyration of the whole ship about the body x, y, z axes through the
        centre of gravity (m).
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
    field
        The case-file field of the ship (``structure[0]``), for messages.
    """

    prescribed_motion = False

    def __init__(self, points, triangles, *, density: float, level: float, gravity,
                 radii_of_gyration, mass: float | None = None, centre_of_gravity=None,
                 initial_displacement=(0.0, 0.0, 0.0), initial_rotation=(0.0, 0.0, 0.0),
                 initial_velocity=(0.0, 0.0, 0.0), initial_angular_velocity=(0.0, 0.0, 0.0),
                 thrust: float = 0.0, surge_speed: float | None = None, ramp_time: float = 0.0,
                 name: str = "ship", field: str = "") -> None:
        self.name, self.field = name, field
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
        self.total_inertia = ship_inertia(self.mass, self.inertia)   # 6 x 6, the whole ship
        self.body_points = self.x_mesh - cg                    # body-frame coordinates, m
        self.cg_mesh = cg                                      # G in the mesh as given, m
        self.q = rotation_quaternion(initial_rotation)
        self.c = cg + np.asarray(initial_displacement, dtype=np.float64).reshape(3)
        self.x0 = self.c + self.body_points @ quaternion_matrix(self.q).T
        self.riders: list = []   # structures riding on the hull (pdfem.motion.attached_frame)
        self.R = quaternion_matrix(self.q)
        self.p, self.L = np.zeros(3), np.zeros(3)
        self._set_body(self.total_inertia, np.asarray(initial_velocity, np.float64).reshape(3),
                       np.asarray(initial_angular_velocity, np.float64).reshape(3))
        self.thrust, self.surge_speed, self.ramp_time = float(thrust), surge_speed, ramp_time
        self.time, self.last_dt = 0.0, 0.0
        self.thrust_work = self.surge_work = 0.0
        # the work (J) of the riders' support loads on the hull (the exchange with them, not
        # booked in the balance) and the impulse (N s) of gravity, water, thrust, held surge
        self.attached_work, self._attached_power = 0.0, 0.0
        self.external_impulse = np.zeros(3)
        self._surface_forces = np.zeros((len(self.x_mesh), 3))
        height = float(np.ptp(self.x_mesh[:, 2]))
        self.datum = np.array([0.0, 0.0, self.level - height])  # m, potential datum
        self._update()
        self._restart()

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
                   surge_speed=s.surge_speed, ramp_time=s.ramp_time, name=cfg.name,
                   field=cfg.field)
        body.patches = surface_patches(path, cfg.contact_group, body.x_mesh,
                                       body.surface_triangles)
        return body

    # ------------------------------------------------------------------ riders
    def attach(self, rider) -> None:
        """A structure rides on the hull from now on (:class:`pdfem.motion.attached_frame
        .AttachedStructure`): the integrated body becomes the whole ship less the riders' free
        degrees of freedom (module docstring), its velocities kept; the riders' stable step
        becomes that of the whole assembly (:func:`pdfem.motion.attached_step
        .assembly_max_eigenvalue`).

        Raises
        ------
        InertiaError
            If the riders carry more mass or inertia than the whole ship's (what is left for
            the rigid hull would not be a body), or leave the integrated body without inertia
            about some axis.
        """
        riders = self.riders + [rider]
        parts = [r.inertia_about(self.cg_mesh) for r in riders]
        problem = hull_inertia_problem(self, riders, parts)
        if problem is not None:
            raise InertiaError(*problem)
        self.riders = riders
        body = self.total_inertia - sum(free for _, free in parts)
        self._set_body(body, self.v, self.omega)
        lam = assembly_max_eigenvalue(body, restoring_stiffness(self), riders, self.cg_mesh)
        for r in riders:
            r.set_max_eigenvalue(lam)
        self._restart()

    def _set_body(self, mass_matrix: np.ndarray, v: np.ndarray, w: np.ndarray) -> None:
        """Integrate the body of the 6 x 6 ``mass_matrix`` (body axes, about G) moving at ``v``
        (m/s, G) and ``w`` (rad/s), world axes: its momenta ``p``, ``L``."""
        self.body_inertia = np.array(mass_matrix, dtype=np.float64)
        self._m_inv = np.linalg.inv(self.body_inertia)
        pi = self.body_inertia @ np.concatenate([self.R.T @ v, self.R.T @ w])
        self.p, self.L = self.R @ pi[:3], self.R @ pi[3:]

    def _restart(self) -> None:
        """The loads on the body with the riders' now, its accelerations, and the riders'
        accelerations with them (after the body or a rider changed)."""
        force, moment = self.force.copy(), self.moment.copy()
        for r in self.riders:
            f, m = r.support_loads_now()
            force, moment = force + f, moment + m
        self._load = (force, moment)
        self._update_velocity()
        self._attached_power = float((force - self.force) @ self.v
                                     + (moment - self.moment) @ self.omega)
        self.rates = self._frame_rates()
        for r in self.riders:
            r.restart()

    # ------------------------------------------------------------------ dynamics
    def _velocities(self, R: np.ndarray, L: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(v, w)``, world axes, of the momenta ``p`` and ``L`` at the attitude ``R``."""
        nu = self._m_inv @ np.concatenate([R.T @ self.p, R.T @ L])
        return R @ nu[:3], R @ nu[3:]

    def _update(self) -> None:
        """Pose, velocities, surface velocities and the external loads at the current state."""
        self.R = quaternion_matrix(self.q)
        self._x = self.c + self.body_points @ self.R.T
        self.hydro = hydrostatics(self._x, self.surface_triangles, self.level, self.density,
                                  self.g, self.c)
        self.thrust_force = self.thrust * self.R[:, 0]
        self.force = self.mass * self.gravity + self.hydro.force + self.thrust_force
        self.moment = self.hydro.moment
        self._update_velocity()

    def _drift(self, h: float) -> None:
        """Move G and turn the hull over ``h`` (s) with the midpoint velocities; ``L`` stays
        the angular momentum about the moved G."""
        v, w = self._velocities(self.R, self.L)
        half = quaternion_matrix(quaternion_product(rotation_quaternion(0.5 * h * w), self.q))
        v, w = self._velocities(half, self.L - cross(0.5 * h * v, self.p))   # at mid-step
        c = self.c + h * v
        q = quaternion_product(rotation_quaternion(h * w), self.q)
        self.q = q / np.linalg.norm(q)
        self.L = self.L - cross(c - self.c, self.p)
        self.c = c

    def step(self, dt: float) -> None:
        """Advance by ``dt`` (s), the riders with the hull (module docstring)."""
        h = float(dt)
        thrust0, force0 = self.thrust_force, self.force
        self.p += 0.5 * h * self._load[0]
        self.L += 0.5 * h * self._load[1]
        c_old = self.c.copy()
        self._drift(h)
        self._update()
        force, moment = self.force.copy(), self.moment.copy()
        for r in self.riders:
            f, m = r.begin_coupled_step(h)
            force, moment = force + f, moment + m
        self._load = (force, moment)
        self.p += 0.5 * h * force
        self.L += 0.5 * h * moment
        self._update_velocity()
        self.thrust_work += float(0.5 * (thrust0 + self.thrust_force) @ (self.c - c_old))
        self.external_impulse += 0.5 * h * (force0 + self.force)
        power = float((force - self.force) @ self.v + (moment - self.moment) @ self.omega)
        self.attached_work += 0.5 * h * (self._attached_power + power)
        self._attached_power = power
        self.time += h
        self.last_dt = h
        self.rates = self._frame_rates()
        for r in self.riders:
            r.end_coupled_step()
        self._hold_surge()

    def _frame_rates(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The body's motion now in body axes, as its riders' inertial loads need it
        (:func:`pdfem.motion.frame_kernels.inertial_loads`): the acceleration of G (m/s^2),
        the angular acceleration (rad/s^2) and velocity (rad/s), from the loads and the
        momenta: ``d/dt (R^T p, R^T L) = R^T (F, M - v x p) - w_b x (R^T p, R^T L)``."""
        R = self.R
        pb, Lb = R.T @ self.p, R.T @ self.L
        nu = self._m_inv @ np.concatenate([pb, Lb])
        vb, wb = nu[:3], nu[3:]
        force, moment = self._load
        dpi = np.concatenate([R.T @ force - cross(wb, pb),
                              R.T @ (moment - cross(self.v, self.p)) - cross(wb, Lb)])
        dnu = self._m_inv @ dpi
        return dnu[:3] + cross(wb, vb), dnu[3:], wb

    def _hold_surge(self) -> None:
        """Hold the surge speed (if given) by an impulse along x at G; book its work."""
        if self.surge_speed is None:
            return
        ramp = 1.0 if self.ramp_time <= 0.0 else min(1.0, self.time / self.ramp_time)
        gain = float(self.R[0] @ self._m_inv[:3, :3] @ self.R[0])   # dv_x per N s along x
        j = np.array([(self.surge_speed * ramp - self.v[0]) / gain, 0.0, 0.0])
        self.surge_work += self._jump(j, np.zeros(3))
        self.external_impulse += j

    def _jump(self, impulse: np.ndarray, moment: np.ndarray) -> float:
        """Jump of ``p`` and ``L`` by an impulse (N s) and its moment about G (N m s); the
        riders' free nodes keep their world velocity. Returns the kinetic-energy change (J)."""
        before, v, w = self.kinetic_energy(), self.v, self.omega
        self.p = self.p + impulse
        self.L = self.L + moment
        self._update_velocity()
        for r in self.riders:
            r.keep_world_velocity(self.v - v, self.omega - w)
        return self.kinetic_energy() - before

    def apply_surface_impulse(self, impulse: np.ndarray) -> float:
        """Jump of ``p`` and ``L`` by the resultant impulse (N s) and its moment about G;
        returns their work, the kinetic-energy change (J)."""
        return self.apply_impulse_at(self._x, impulse)

    def apply_impulse_at(self, points: np.ndarray, impulse: np.ndarray) -> float:
        """Impulses (N s, (N, 3), world) on the hull at ``points`` (m): the ice's, or a
        rider's on its supported nodes. Returns their work, the kinetic-energy change (J)."""
        j = np.asarray(impulse, dtype=np.float64).reshape(-1, 3)
        arm = np.asarray(points, dtype=np.float64).reshape(-1, 3) - self.c
        work = self._jump(j.sum(axis=0), cross(arm, j).sum(axis=0))
        self._hold_surge()
        return work

    def _update_velocity(self) -> None:
        """Velocities and surface velocities after a change of the momenta or the pose."""
        self.v, self.omega = self._velocities(self.R, self.L)
        self._v = self.v + cross(self.omega, self._x - self.c)

    # ------------------------------------------------------------------ energies
    def kinetic_energy(self) -> float:
        """``(v . p + w . L) / 2`` (J): the integrated body's (without riders, the ship's
        ``m v^2 / 2 + L . w / 2``)."""
        return 0.5 * float(self.v @ self.p) + 0.5 * float(self.L @ self.omega)

    def potential_energy(self) -> float:
        """Gravity and hydrostatic potential (J): ``-m g . (c - c_datum) + rho g int_V (level - z)
        dV`` with ``c_datum`` the hull's height H below the water surface."""
        return (-self.mass * float(self.gravity @ (self.c - self.datum))
                + self.hydro.potential)

    def energy_terms(self) -> dict[str, float]:
        """``load_work``: work of the thrust (J); ``support_work``: of holding the surge
        speed; ``kinetic_correction``: ``-(h^2/8) a . M_B a`` of the last step ``h`` with the
        acceleration of the loads ``a = M_B^-1 (R^T F, R^T M)`` (velocity Verlet's kinetic
        energy is conserved with it, as the central differences' of
        :mod:`pdfem.fem.explicit`)."""
        phi = np.concatenate([self.R.T @ self._load[0], self.R.T @ self._load[1]])
        return {"load_work": self.thrust_work, "support_work": self.surge_work,
                "damping_dissipated": 0.0,
                "kinetic_correction": -0.125 * self.last_dt ** 2 * float(phi @ self._m_inv @ phi)}

    def applied_load(self) -> np.ndarray:
        """(3,) gravity + hydrostatic force + thrust now (N)."""
        return self.force.copy()

    # ------------------------------------------------------------------ output
    def motion_history(self) -> dict[str, np.ndarray | float]:
        """One row every coupling step: ``position`` of the centre of gravity (m),
        ``rotation`` vector (rad, from the hull as given), ``velocity`` (m/s),
        ``angular_velocity`` (rad/s, world axes), ``hydrostatic_force`` (N),
        ``hydrostatic_moment`` (N m, about the centre of gravity); ``attached_impulse`` (N s,
        the impulse the structures riding on the hull have passed on to the ship as a whole so
        far: their external impulses less the change of their elastic momentum,
        :meth:`pdfem.motion.attached_frame.AttachedStructure.handed_impulse`), ``attached_work``
        (J, the work of their support loads on the integrated body, an exchange inside the
        ship, not in the energy balance), ``external_impulse`` (N s) of gravity, water, thrust
        and held surge so far."""
        return {"position": self.c.copy(), "rotation": rotation_vector(self.q),
                "velocity": self.v.copy(), "angular_velocity": self.omega.copy(),
                "hydrostatic_force": self.hydro.force.copy(),
                "hydrostatic_moment": self.hydro.moment.copy(),
                "attached_impulse": sum((r.handed_impulse() for r in self.riders), np.zeros(3)),
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
        """Mass, displacement, inertia (and what rides on the hull)."""
        riders = ""
        if self.riders:
            m = float(np.trace(self.body_inertia[:3, :3])) / 3.0
            riders = (f"; carries {', '.join(repr(r.name) for r in self.riders)}: the hull "
                      f"with their supports integrated as one body of {m:.4g} kg")
        return (f"ship '{self.name}': {len(self.x_mesh):,} hull nodes, mass {self.mass:.4g} kg, "
                f"displacement at start {self.density * self.hydro.volume:.4g} kg, "
                f"I = {np.array2string(self.inertia, precision=4)} kg m^2{riders}")

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
        """c, q, p, L, the loads on the body, time and the work counters."""
        return {"c": self.c.copy(), "q": self.q.copy(), "p": self.p.copy(), "L": self.L.copy(),
                "load": np.concatenate(self._load), "time": self.time, "last_dt": self.last_dt,
                "thrust_work": self.thrust_work, "surge_work": self.surge_work,
                "surface_forces": self._surface_forces.copy(),
                "attached": np.concatenate([self.external_impulse, [self.attached_work,
                                                                    self._attached_power]])}

    def restore_state(self, state: dict) -> None:
        """Restore a state from :meth:`checkpoint_state` exactly."""
        for key in ("c", "p", "L"):
            setattr(self, key, np.array(state[key], dtype=np.float64).reshape(3))
        self.q = np.array(state["q"], dtype=np.float64).reshape(4)
        load = np.array(state["load"], dtype=np.float64)
        self._load = (load[:3].copy(), load[3:].copy())
        self.time, self.last_dt = float(state["time"]), float(state["last_dt"])
        self.thrust_work, self.surge_work = float(state["thrust_work"]), float(state["surge_work"])
        self._surface_forces[:] = state["surface_forces"]
        self._update()
        self.rates = self._frame_rates()
        a = np.array(state["attached"], dtype=np.float64)
        self.external_impulse = a[:3].copy()
        self.attached_work, self._attached_power = float(a[3]), float(a[4])


class InertiaError(ValueError):
    """Structures attached to a ship that carry more mass or inertia than the whole ship's
    (:meth:`Ship.attach`).

    Parameters
    ----------
    key
        The ship's input that is too small: ``"mass"`` or ``"radii_of_gyration"``.
    message
        What is wrong and what would be valid.
    """

    def __init__(self, key: str, message: str) -> None:
        super().__init__(message)
        self.key = key
