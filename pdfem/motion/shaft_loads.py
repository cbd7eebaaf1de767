"""Shaft and blade loads of a rotating elastic structure (a propeller): ice torque and thrust,
the shaft's torque, work and angular impulse, per-blade forces, spindle torque and root bending
moments, and the largest von Mises stress (docs/rotating_structures.md, "Shaft and blade loads").

A :class:`ShaftLoads` belongs to a :class:`pdfem.motion.frame_structure.FrameStructure` whose frame turns
(shaft axis ``n`` = the unit ``angular_velocity`` through ``center``). It is fed by two hooks:

* every contact impulse ``J`` (world axes, on the contact-surface nodes) at the instant it is
  applied (:meth:`ShaftLoads.add_impulse`): kept per node in world axes and in frame axes with
  its moment ``r x J`` (frame axes, ``r = X - c0 + u_e`` the node's position from the shaft
  centre), so moments about any point fixed in the frame (a blade's root) are exact;
* every structure step (:meth:`ShaftLoads.after_step`): the force the supports exert on the
  structure node by node (``K u + C v + M a - f_ext`` on the held DOFs, frame axes; it includes
  the inertial loads on the held nodes, so it is the true force of the hub on the blade roots),
  whose moment about the axis is the **shaft torque** and whose power on the nodes' true
  velocity is the **shaft power**; both are integrated by the trapezoid rule, which is how the
  central-difference scheme integrates a force into momentum.

Sign conventions (SI units: N, N m, N m s, W, J, Pa, m, rad):

* ``ice_torque`` = ``-n . M_ice``: the moment of the ice's force about the shaft axis, positive
  when it opposes the rotation; ``thrust`` = ``n . F_ice``: the ice's force along the axis,
  positive along ``angular_velocity``;
* ``shaft_torque`` = ``n . M_shaft``: the moment the shaft puts on the structure, positive in
  the direction of rotation (at constant speed in a steady state it balances ``ice_torque``):
  the supports' forces, plus the Rayleigh mass-damping forces on the free nodes (damping acts
  on the motion relative to the frame, so its force is one between the structure and the
  frame, which the shaft drives; zero without damping or at rest); ``shaft_power`` (W) is
  their power on the frame's velocity at the nodes;
* blade axes (frame, fixed to blade k of Z): ``e_r`` radial along the spindle, the radial line
  at ``psi_k = 2 pi (k - 1) / Z`` about the axis from +z (the propeller model's reference
  line, :func:`spindle`; the radial direction of the root centroid when that line is not near
  it, e.g. for an axis along z), ``e_t = n x e_r`` tangential (the direction the blade moves
  in), ``e_a = n`` axial. ``force_blade`` = the ice's force on the blade in (e_r, e_t, e_a);
  the moment ``M`` of the ice's force about the root section's centroid (the centroid of the
  nodes of ``blade{k}_root``) gives ``spindle_torque = e_r . M``, ``bending_out_of_plane =
  e_t . M`` (bending out of the plane of rotation, from axial loads) and ``bending_in_plane =
  e_a . M`` (in the plane of rotation, from tangential loads). These are the ice-load moments
  at the root section (the quasi-static part, without the blade's own inertia and centrifugal
  load). ``root_moment`` (e_r, e_t, e_a components: spindle, out of plane, in plane) is the
  moment the blade puts on its supports at the held nodes of ``blade{k}_root`` about the root
  centroid, ``-sum (r - p) x R`` with the supports' nodal forces R: the whole root-section
  moment, with the blade's inertia and centrifugal load (zero if the root is not held).
  ``root_stress_tension``, ``root_stress_compression`` and ``root_stress_axial`` (Pa) are the
  blade's nominal root stress by the cantilever-beam method (:mod:`pdfem.fem.section_stress`):
  the supports' resultant force and moment at the root section over its area and second
  moments (the section projected onto the plane normal to ``e_r``), the largest and smallest
  normal stress over the section and the axial part ``F / A``. Unlike the elastic stress at
  the clamped root edge (singular there), it converges under mesh refinement.

Rows (every coupling step; forces are the step's impulses over its length): ``shaft/<name>``:
``frame_angle`` (rad), ``ice_torque``, ``thrust``, ``ice_force`` (3, world), ``shaft_torque``,
``shaft_power``, the running integrals ``shaft_work``, ``shaft_angular_impulse``, ``ice_work``
(world, on the true velocity), ``ice_angular_impulse`` (opposing positive), the changes since
t = 0 of the angular momentum about the axis (``angular_momentum_change``, true motion) and of
the energy (``energy_change``: true kinetic energy with the lumped mass plus strain energy),
``damping_dissipated``, and ``max_von_mises`` (Pa, element centres) with its element's centre
``max_von_mises_location`` (m, reference position in frame axes at t = 0); ``shaft/<name>.blade<k>``:
``force`` (world), ``force_blade``, ``ice_torque``, ``thrust``, ``spindle_torque``,
``bending_out_of_plane``, ``bending_in_plane``, ``root_moment``, ``root_stress_tension``,
``root_stress_compression``, ``root_stress_axial`` (when the root is a surface group),
``max_von_mises`` (over the elements of the volume group ``blade<k>``, else all) and its
location.

Blades are found by the mesh's surface groups ``blade{k}_surface`` (k = 1, 2, ...); without
them the whole contact surface is one blade whose root is the union of the clamped groups.
"""

from __future__ import annotations

import re

import numpy as np
import scipy.sparse as sp

from pdfem.fem.section_stress import Section, section_of, stress_range
from pdfem.geometry.vectors import cross
from pdfem.motion.frame_kernels import StepVectors, momentum_energy, support_torque_power
from pdfem.motion.stress_peaks import StressPeaks
from pdfem.parallel.comm import SerialComm

BLADE_SURFACE = re.compile(r"blade(\d+)_surface\Z")
"""Name of blade k's surface group (its faces but the root)."""


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def blade_groups(structure) -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray]]:
    """``[(label, surface-node mask (Ns,) bool, root nodes, root faces)]`` of the blades of
    ``structure``: ``blade{k}`` from the groups ``blade{k}_surface`` and ``blade{k}_root`` of
    its mesh (the root falls back on the clamped groups), in k order; else one ``blade1``, the
    whole contact surface with the clamped groups as its root. The root faces are the (F, 3 or
    4) corner nodes of the root's mesh faces: none when the root is no surface group, and none
    for a blade of several without a root group of its own (the clamped faces of every blade
    are no section of one)."""
    found = sorted((int(m.group(1)), g) for g in structure.mesh.facet_sets
                   if (m := BLADE_SURFACE.match(g)))
    held = np.unique(np.concatenate([structure.group_nodes(g) for g in structure.fixed_groups]
                                    or [np.zeros(0, np.int32)]))
    held_faces = [structure.mesh.group_facets(g) for g in structure.fixed_groups
                  if g in structure.mesh.facet_sets]
    held_faces = np.vstack(held_faces) if held_faces else np.zeros((0, 3), np.int32)
    if not found:
        return [("blade1", np.ones(len(structure.surface_nodes), bool), held, held_faces)]
    out = []
    for k, g in found:
        mask = np.isin(structure.surface_nodes, structure.group_nodes(g))
        root = f"blade{k}_root"
        own = root in structure.mesh.facet_sets
        faces = (structure.mesh.group_facets(root) if own
                 else held_faces if len(found) == 1 else np.zeros((0, 3), np.int32))
        out.append((f"blade{k}", mask, structure.group_nodes(root) if own else held, faces))
    return out


def spindle(axis: np.ndarray, psi: float, point: np.ndarray) -> np.ndarray:
    """Unit spindle direction (frame axes) of a blade: the radial line at ``psi`` (rad) about
    the shaft ``axis`` from +z (the propeller model's reference line, either sense of ``psi``:
    the one nearer the blade), when it lies within 30 deg of the radial direction of ``point``
    (m from the shaft centre: the root centroid); else (an axis along z, or another layout)
    that radial direction."""
    radial = _unit(point - (point @ axis) * axis)
    z = np.array([0.0, 0.0, 1.0]) - axis[2] * axis
    if np.linalg.norm(z) < 1e-6:
        return radial
    z = _unit(z)
    best = max((np.cos(a) * z + np.sin(a) * cross(axis, z) for a in (psi, -psi)),
               key=lambda e: float(e @ radial))
    return best if best @ radial > np.cos(np.radians(30.0)) else radial


def root_stress(section: Section, force: np.ndarray, moment: np.ndarray) -> dict[str, float]:
    """A blade's nominal root stress (Pa, :mod:`pdfem.fem.section_stress`) from the force (N)
    and the moment about the section's centroid (N m) that the blade puts on its supports,
    frame axes: ``root_stress_tension`` (the largest over the section),
    ``root_stress_compression`` (the smallest) and ``root_stress_axial`` (``F / A``)."""
    tension, compression, axial = stress_range(section, section.axes @ force,
                                               section.axes @ moment)
    return {"root_stress_tension": tension, "root_stress_compression": compression,
            "root_stress_axial": axial}


def gradient_operator(basis) -> sp.csr_matrix:
    """(9 Ne, n DOFs) sparse operator giving ``du_i/dx_j`` at the one evaluation point of each
    element of a :func:`pdfem.fem.stress.centre_basis` (row ``(3 i + j) Ne + e``, 1/1): the
    displacement gradient of :func:`pdfem.fem.stress.element_stress` as one product."""
    dofs = basis.element_dofs                                  # (Nb, Ne)
    ne = dofs.shape[1]
    rows, cols, vals = [], [], []
    for a in range(dofs.shape[0]):
        g = basis.basis[a][0].grad[:, :, :, 0]                 # (3, 3, Ne)
        for i in range(3):
            for j in range(3):
                rows.append((3 * i + j) * ne + np.arange(ne))
                cols.append(dofs[a])
                vals.append(g[i, j])
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                         shape=(9 * ne, basis.N))


class ShaftLoads:
    """Shaft and blade loads of one rotating frame structure (module docstring).

    Parameters
    ----------
    structure
        A :class:`pdfem.motion.frame_structure.FrameStructure` whose frame turns (non-zero
        ``angular_velocity``).
    comm
        The ranks that share the blades' stresses (:class:`pdfem.motion.stress_peaks.StressPeaks`);
        default one process.
    """

    def __init__(self, structure, comm=SerialComm()) -> None:
        self.structure = structure
        frame = structure.frame
        self.axis = _unit(np.asarray(frame.angular_velocity, dtype=np.float64))
        self.center = np.asarray(frame.center, dtype=np.float64)
        r0 = structure.points - self.center
        self.blades = []
        groups = blade_groups(structure)
        self._roots = [root for _, _, root, _ in groups]
        self._sections: list[Section | None] = []
        for k, (label, mask, root, faces) in enumerate(groups):
            p = r0[root].mean(axis=0) if len(root) else r0[structure.surface_nodes[mask]].mean(0)
            e_r = spindle(self.axis, 2.0 * np.pi * k / len(groups),
                          r0[structure.surface_nodes[mask]].mean(axis=0) if len(root) == 0
                          or np.linalg.norm(p - (p @ self.axis) * self.axis) < 1e-9 else p)
            axes = np.array([e_r, cross(self.axis, e_r), self.axis])  # rows: e_r, e_t, e_a
            self.blades.append((label, mask, p, axes))
            self._sections.append(section_of(r0, structure.space.face_triangles(faces), axes)
                                  if len(faces) else None)
        self._held = structure.solver.fixed                       # held DOFs
        self._held_mask = ~structure.solver.free
        table = structure.dofmap.nodal_dofs                       # (3, Nn) DOF of each node
        self._dofs = np.ascontiguousarray(table, dtype=np.int64)
        node = np.empty(structure.dofmap.n_dofs, dtype=np.int64)
        node[table.ravel()] = np.tile(np.arange(table.shape[1]), 3)
        comp = np.empty(structure.dofmap.n_dofs, dtype=np.int64)
        comp[table.ravel()] = np.repeat(np.arange(3), table.shape[1])
        self._held_nodes, self._held_row = np.unique(node[self._held], return_inverse=True)
        self._held_comp = comp[self._held]
        self._all_nodes = np.arange(structure.n_nodes)
        self._cells = structure.cells                             # (Ne, k) FE nodes
        # the peak element stresses, overall and per blade (u -> du_i/dx_j at the centres)
        self._peaks = StressPeaks(gradient_operator(structure.stress_basis), structure.material,
                                  [structure.mesh.element_sets.get(b[0]) for b in self.blades],
                                  comm)
        self._root_rows = [np.flatnonzero(np.isin(self._held_nodes, root)) for root in self._roots]
        self._r0 = r0                                             # m, X - c0
        n = len(structure.surface_nodes)
        # (B, Ns) 1 where a surface node is on blade b: a blade's sums as one product
        self._on_blade = np.array([mask for _, mask, _, _ in self.blades], dtype=np.float64
                                  ).reshape(len(self.blades), n)
        self.impulse_world = np.zeros((n, 3))    # N s, since the last row
        self.impulse_frame = np.zeros((n, 3))    # N s, frame axes
        self.moment_frame = np.zeros((n, 3))     # N m s, r x J, frame axes
        self.last_time = structure.solver.time   # s, time of the last row
        self.ice_work = 0.0                      # J, the ice's work on the structure (world)
        self.ice_angular_impulse = 0.0           # N m s, about the axis, opposing positive
        q, p = self.support_torque_power()
        self.shaft_torque, self.shaft_power = q, p
        self._last_dt = 0.0                      # s, the last step (amend_step)
        self.shaft_work = 0.0                    # J
        self.shaft_angular_impulse = 0.0         # N m s
        momentum, energy = self.momentum_energy()
        self.energy0 = energy + self.strain_energy()       # J, at the start
        self.angular_momentum0 = momentum                  # kg m^2/s

    def distribute(self, comm) -> None:
        """Share the blades' element stresses over the ranks of ``comm``
        (:meth:`pdfem.motion.stress_peaks.StressPeaks.distribute`)."""
        self._peaks.distribute(comm)

    # ------------------------------------------------------------------ hooks
    def add_impulse(self, impulse: np.ndarray, rotation: np.ndarray, r: np.ndarray,
                    work: float) -> None:
        """Contact impulses (N s, (Ns, 3), world axes) applied now to the surface nodes at
        ``r`` (m, (Ns, 3), frame axes from the shaft centre), with the frame's ``rotation`` and
        their ``work`` (J, world)."""
        jf = impulse @ rotation
        m = cross(r, jf)
        self.impulse_world += impulse
        self.impulse_frame += jf
        self.moment_frame += m
        self.ice_work += work
        self.ice_angular_impulse -= float(m.sum(axis=0) @ self.axis)

    def held_reactions(self) -> np.ndarray:
        """(H, 3) force (N, frame axes) of the supports on each held node (``_held_nodes``)."""
        sol = self.structure.solver
        d = self._held
        reaction = sol.stiffness_force()[d] + sol.f_damp[d] + sol.m[d] * sol.a[d] - sol.f_ext[d]
        force = np.zeros((len(self._held_nodes), 3))
        np.add.at(force, (self._held_row, self._held_comp), reaction)
        return force

    def support_torque_power(self) -> tuple[float, float]:
        """The shaft's moment about the shaft axis (N m, positive in the rotation's sense) and
        its power (W) now: the supports' forces on the held nodes (``K u + C v + M a - f_ext``
        on the held DOFs), plus the Rayleigh mass-damping forces ``-alpha m u_e'`` on the free
        nodes (a force between the structure and the frame, which the shaft drives; the
        stiffness-proportional part is internal), on the frame's velocity at the nodes
        (one pass, :func:`pdfem.motion.frame_kernels.support_torque_power`)."""
        s = self.structure
        sol = s.solver
        f = s.frame.state(sol.time)
        torque, power = support_torque_power(
            self._all_nodes if sol.alpha else self._held_nodes, self._r0, self._dofs,
            self._held_mask, StepVectors(sol.u, sol.stiffness_force(), sol.f_damp, sol.m, sol.a,
                                         sol.f_ext, sol.v_half),
            sol.alpha, np.array([f["R"].T @ f["c_dot"], f["w"], self.axis]))
        return float(torque), float(power)

    def after_step(self, dt: float) -> None:
        """After a structure step of ``dt`` (s): integrate the shaft's torque and power."""
        q, p = self.support_torque_power()
        self.shaft_angular_impulse += 0.5 * (self.shaft_torque + q) * dt
        self.shaft_work += 0.5 * (self.shaft_power + p) * dt
        self.shaft_torque, self.shaft_power = q, p
        self._last_dt = dt

    def amend_step(self) -> None:
        """After the last step's end state was amended (contact impulses on an implicit step,
        :meth:`pdfem.fem.implicit.Newmark.end_impulse`): the shaft's torque and power at its
        end again, and their integrals over it with them."""
        q, p = self.support_torque_power()
        self.shaft_angular_impulse += 0.5 * (q - self.shaft_torque) * self._last_dt
        self.shaft_work += 0.5 * (p - self.shaft_power) * self._last_dt
        self.shaft_torque, self.shaft_power = q, p

    # ------------------------------------------------------------------ state
    def momentum_energy(self) -> tuple[float, float]:
        """The structure's angular momentum about the shaft axis (kg m^2/s) and its kinetic
        energy in the world (J), true motion, lumped mass (one pass,
        :func:`pdfem.motion.frame_kernels.momentum_energy`)."""
        s = self.structure
        f = s.frame.state(s.solver.time)
        momentum, energy = momentum_energy(self._r0, s.solver.u, s.solver.v, self._dofs,
                                           s.node_mass, f["R"], f["c_dot"], f["w"], self.axis)
        return float(momentum), float(energy)

    def strain_energy(self) -> float:
        """Strain energy ``1/2 u . K u`` (J), with the integrator's ``K u`` (no product)."""
        sol = self.structure.solver
        return 0.5 * float(np.einsum("i,i", sol.u, sol.stiffness_force()))  # not BLAS

    def _centre(self, element: int) -> np.ndarray:
        """The centre (m, reference, frame axes at t = 0) of ``element``."""
        return self.structure.points[self._cells[element]].mean(axis=0)

    def rows(self) -> dict[str, dict[str, float | np.ndarray]]:
        """The rows of the coupling step ending now (forces are the step's impulses over its
        length) and restart the step's sums: ``""`` (the shaft) and one per blade label, each
        blade's on the rank that evaluates its stresses (shared with its peak). Collective
        when the blades are dealt out."""
        s = self.structure
        step = s.solver.time - self.last_time
        scale = 1.0 / step if step > 0.0 else 0.0
        force = self.impulse_world.sum(axis=0) * scale
        moment = self.moment_frame.sum(axis=0) * scale
        held = self.held_reactions()
        r_held = self._r0[self._held_nodes] + s.dofmap.to_nodal(s.solver.u)[self._held_nodes]
        (peak, element), _, blade_rows = self._peaks.peaks_with(
            s.solver.u, lambda b, bpeak: self._blade_row(b, bpeak, held, r_held, scale))
        momentum, energy = self.momentum_energy()
        out = {"": {"frame_angle": s.frame.angle(s.solver.time),
                    "ice_torque": -float(moment @ self.axis), "thrust": float(force @ self.axis),
                    "ice_force": force, "shaft_torque": self.shaft_torque,
                    "shaft_power": self.shaft_power, "shaft_work": self.shaft_work,
                    "shaft_angular_impulse": self.shaft_angular_impulse,
                    "ice_work": self.ice_work, "ice_angular_impulse": self.ice_angular_impulse,
                    "angular_momentum_change": momentum - self.angular_momentum0,
                    "energy_change": energy + self.strain_energy() - self.energy0,
                    "damping_dissipated": s.solver.damping_dissipated,
                    "max_von_mises": peak,
                    "max_von_mises_location": self._centre(element)}}
        out.update((blade[0], row) for blade, row in zip(self.blades, blade_rows))
        self.impulse_world[:] = 0.0
        self.impulse_frame[:] = 0.0
        self.moment_frame[:] = 0.0
        self.last_time = s.solver.time
        return out

    def _blade_row(self, b: int, peak: tuple[float, int], held: np.ndarray, r_held: np.ndarray,
                   scale: float) -> dict[str, float | np.ndarray]:
        """Blade ``b``'s row: the ice's loads on it (its impulses times ``scale``, 1/s), its
        root moment and stresses from the supports' forces ``held`` (N) on the held nodes at
        ``r_held`` (m, frame axes from the centre), and its element stress ``peak`` (Pa,
        element)."""
        _, _, p, axes = self.blades[b]
        rows, section, on = self._root_rows[b], self._sections[b], self._on_blade[b]
        j_world, j_frame, m_frame = (on @ self.impulse_world, on @ self.impulse_frame,
                                     on @ self.moment_frame)
        root_moment = -cross(r_held[rows] - p, held[rows]).sum(axis=0)
        jf = j_frame * scale
        m = (m_frame - cross(p, j_frame)) * scale
        row = {"force": j_world * scale,
               "force_blade": axes @ jf,
               "ice_torque": -float(m_frame @ self.axis) * scale,
               "thrust": float(jf @ self.axis),
               "spindle_torque": float(axes[0] @ m),
               "bending_out_of_plane": float(axes[1] @ m),
               "bending_in_plane": float(axes[2] @ m),
               "root_moment": axes @ root_moment,
               "max_von_mises": peak[0],
               "max_von_mises_location": self._centre(peak[1])}
        if section is not None:   # the same resultants about the section's centroid
            force_on_root = -held[rows].sum(axis=0)
            row.update(root_stress(section, force_on_root,
                                   root_moment + cross(p - section.centroid, force_on_root)))
        return row

    def checkpoint_state(self) -> dict[str, np.ndarray | float]:
        """The step's sums and the running integrals, for a checkpoint."""
        return {"shaft_impulse_world": self.impulse_world.copy(),
                "shaft_impulse_frame": self.impulse_frame.copy(),
                "shaft_moment_frame": self.moment_frame.copy(),
                "shaft_scalars": np.array([self.last_time, self.ice_work,
                                           self.ice_angular_impulse, self.shaft_torque,
                                           self.shaft_power, self.shaft_work,
                                           self.shaft_angular_impulse, self.energy0,
                                           self.angular_momentum0])}

    def restore_state(self, state: dict) -> None:
        """Restore :meth:`checkpoint_state` exactly."""
        self.impulse_world = np.array(state["shaft_impulse_world"], dtype=np.float64)
        self.impulse_frame = np.array(state["shaft_impulse_frame"], dtype=np.float64)
        self.moment_frame = np.array(state["shaft_moment_frame"], dtype=np.float64)
        (self.last_time, self.ice_work, self.ice_angular_impulse, self.shaft_torque,
         self.shaft_power, self.shaft_work, self.shaft_angular_impulse, self.energy0,
         self.angular_momentum0) = map(
            float, state["shaft_scalars"])
