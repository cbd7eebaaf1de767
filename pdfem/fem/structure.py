"""An elastic structure: FE model, explicit solver state, loads and the contact surface.

:class:`ElasticStructure` ties together a mesh (:mod:`pdfem.fem.mesh`), the assembled stiffness
and lumped mass (:mod:`pdfem.fem.elasticity`), the central-difference solver
(:mod:`pdfem.fem.explicit`) and stress recovery (:mod:`pdfem.fem.stress`). The elements are
quadratic by default (``element_order = 2``: 10-node tetrahedra or 20-node serendipity
hexahedra with HRZ lumped mass, :mod:`pdfem.fem.fe_space`; first-order elements lock in bending,
docs/structures_convergence.md). Nodes are FE nodes: every DOF location (mesh vertices first,
then the midside nodes). Named groups of the mesh give the supports (:mod:`pdfem.fem.supports`:
clamped, per component, prescribed) and the contact surface (each face split into linear
triangles over all its nodes), which the contact code reaches through the
:class:`pdfem.fem.surface.ContactSurface` interface shared with rigid bodies.

Forces: the applied loads of :class:`pdfem.fem.loads.AppliedLoads` plus the contact forces.

Small displacements: stiffness, loads and stresses use the reference configuration; surface
positions and normals reported to the contact code use the current one (reference + u).
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

import numpy as np

from pdfem.errors import InstabilityError
from pdfem.fem.base import Structure
from pdfem.fem.elasticity import (DofMap, ElasticMaterial, element_volumes, lumped_mass,
                                  stiffness_matrix)
from pdfem.fem.explicit import CentralDifference
from pdfem.fem.fe_space import fe_space, hrz_mass
from pdfem.fem.implicit import Newmark
from pdfem.fem.loads import AppliedLoads
from pdfem.fem.mesh import FEMesh, load_mesh
from pdfem.fem.probe import Probe, make_probe, probe_values
from pdfem.fem.stress import (centre_basis, element_stress, kinetic_energy, nodal_average,
                              von_mises)
from pdfem.fem.step_compliance import (Coupling, LumpedCompliance, StepCompliance,
                                      decay_length, wave_speed)
from pdfem.fem.supports import (constrained_dofs, prescribed_values, support_reaction,
                                support_table)
from pdfem.fem.surface_motion import PredictedSurface, SteppedSurface
from pdfem.meshing.quality import check_cells


INTEGRATORS = {"explicit": CentralDifference, "implicit": Newmark}
"""Time integrators of an elastic structure by the case's ``integrator`` name."""


class ElasticStructure(AppliedLoads, Structure):
    """A linear-elastic FE structure advanced by explicit central differences or implicit
    Newmark steps (a :class:`pdfem.fem.base.Structure`).

    Parameters
    ----------
    mesh
        The volume mesh with its named groups.
    material
        Density (kg/m^3), Young's modulus (Pa), Poisson's ratio.
    fixed_groups
        Names of groups whose nodes are clamped (u = 0).
    supports
        ``{group: components}``: only the named components (``"x"``, ``"y"``, ``"z"``) of the
        group's nodes held at zero (rollers, symmetry planes).
    contact_group
        Name of the surface group the contact code sees (``None``: no contact surface).
    prescribed
        ``{group: displacement}``: the nodes of each group move with a uniform prescribed
        displacement (m), a (3,) vector or a callable ``t -> (3,)`` of the time (s). Nodes in
        both a fixed and a prescribed group follow the prescribed displacement.
    name
        Name of the structure (for messages and output).
    rayleigh_alpha, rayleigh_beta
        Rayleigh damping ``C = alpha M + beta K`` (alpha in 1/s, beta in s).
    safety_factor
        Factor on the critical step in :meth:`stable_time_step`.
    max_eigenvalue
        A known ``omega_max^2`` (1/s^2) of the constrained system, to skip the power iteration.
    element_order
        2 (default): 10-node tetrahedra / 20-node serendipity hexahedra on the (first-order)
        mesh; 1: 4-node tetrahedra / 8-node hexahedra (they lock in bending).
    integrator
        ``"explicit"`` (default: central differences, :mod:`pdfem.fem.explicit`) or
        ``"implicit"`` (average-acceleration Newmark, unconditionally stable,
        :mod:`pdfem.fem.implicit`); a key of :data:`INTEGRATORS`.

    Raises
    ------
    ValueError
        If a named group is missing (the message lists the groups of the file).
    """

    def __init__(self, mesh: FEMesh, material: ElasticMaterial, fixed_groups: Sequence[str] = (),
                 contact_group: str | None = None, prescribed: Mapping | None = None,
                 name: str = "structure",
                 rayleigh_alpha: float = 0.0, rayleigh_beta: float = 0.0,
                 safety_factor: float = 0.9, max_eigenvalue: float | None = None,
                 supports: Mapping[str, Sequence[str]] | None = None, element_order: int = 2,
                 integrator: str = "explicit"):
        if isinstance(fixed_groups, str):
            fixed_groups = [fixed_groups]
        prescribed = dict(prescribed or {})
        self.supports = support_table(fixed_groups, supports, prescribed)
        for g in self.supports:  # check names before the assembly
            mesh.group_nodes(g)
        if contact_group is not None:
            mesh.group_facets(contact_group)
        self.name = name
        self.mesh = mesh
        self.material = material
        self.fixed_groups = list(fixed_groups)
        self._component_supports = set(supports or {})
        self.contact_group = contact_group
        self.space = fe_space(mesh, element_order)
        self.basis = self.space.basis
        self.dofmap = DofMap(self.space.nodal_dofs)
        self.K = stiffness_matrix(self.basis, material)
        self.mass = (lumped_mass(self.basis, material.density) if element_order == 1
                     else hrz_mass(self.basis, material.density))
        fixed = constrained_dofs(self.dofmap, self.group_nodes, self.supports)
        self.solver = INTEGRATORS[integrator](
            self.K, self.mass, fixed, rayleigh_alpha=rayleigh_alpha, rayleigh_beta=rayleigh_beta,
            safety_factor=safety_factor, max_eigenvalue=max_eigenvalue)
        if prescribed:
            self.solver.prescribe(prescribed_values(self.solver.fixed, self.dofmap,
                                                    self.group_nodes, prescribed))
        self.node_points = self.space.points
        self.stress_basis = centre_basis(mesh, self.space.element)
        self._volumes = element_volumes(mesh)
        faces = (mesh.group_facets(contact_group) if contact_group is not None
                 else np.zeros((0, 3), dtype=np.int32))
        nodes, local = np.unique(self.space.face_triangles(faces), return_inverse=True)
        self.surface_nodes = nodes.astype(np.int32)
        self.surface_triangles = local.reshape(-1, 3).astype(np.int32)
        self._surface_forces = np.zeros((len(self.surface_nodes), 3))
        # DOF index of (surface node, component), node-major like _surface_forces.ravel()
        self._surface_dofs = self.dofmap.nodal_dofs[:, self.surface_nodes].T.ravel()
        self._surface_points0 = self.node_points[self.surface_nodes]
        self._nodal_forces = np.zeros((self.n_nodes, 3))
        self.implicit = self.solver.steps_before_contact   # implicit steps (Newmark)
        # (dt, the surface's compliance for that step): surface_compliance's, kept
        self._compliance: tuple[float, LumpedCompliance | StepCompliance] | None = None
        self._pressure_dofs = np.zeros(self.dofmap.n_dofs)
        self._load_dofs = np.zeros(self.dofmap.n_dofs)   # nodal forces + surface loads, as DOFs
        self._timed_loads: list = []                      # (DOF vector, t -> factor)
        self.solver.initialize()

    def surface_groups(self) -> dict[str, np.ndarray]:
        """``{surface group: (T,) bool}``: which contact-surface triangles lie on each other
        surface group of the mesh that shares faces with the contact group (load patches)."""
        if self.contact_group is None:
            return {}
        own = self.mesh.group_facet_indices(self.contact_group)
        per_face = len(self.surface_triangles) // len(own)   # triangles of one face, in order
        found = {}
        for group, faces in sorted(self.mesh.facet_indices.items()):
            on = np.repeat(np.isin(own, faces), per_face)
            if group != self.contact_group and on.any():
                found[group] = on
        return found

    def group_nodes(self, name: str) -> np.ndarray:
        """Sorted int32 FE nodes of a named group, midside nodes on its edges, faces and
        elements included (:meth:`pdfem.fem.fe_space.FESpace.group_nodes`)."""
        return self.space.group_nodes(name)

    @classmethod
    def from_file(cls, path: str | os.PathLike, material: ElasticMaterial,
                  **kwargs) -> "ElasticStructure":
        """Build from a gmsh ``.msh`` file; ``kwargs`` as for the constructor."""
        return cls(load_mesh(path), material, **kwargs)

    # ------------------------------------------------------------------ geometry
    @property
    def points(self) -> np.ndarray:
        """(Nn, 3) reference FE node coordinates (m)."""
        return self.node_points

    @property
    def n_nodes(self) -> int:
        """Number of FE nodes Nn."""
        return self.space.n_nodes

    @property
    def cell_type(self) -> str:
        """meshio cell type: ``tetra``, ``tetra10``, ``hexahedron`` or ``hexahedron20``."""
        return self.space.cell_type

    @property
    def cells(self) -> np.ndarray:
        """(Ne, 4, 10, 8 or 20) int32 connectivity over FE nodes in meshio / VTK node order."""
        return self.space.cells()

    @property
    def time(self) -> float:
        """Current time (s)."""
        return self.solver.time

    # ------------------------------------------------------------------ state
    def displacement(self) -> np.ndarray:
        """(Nn, 3) displacement (m)."""
        return self.dofmap.to_nodal(self.solver.u).copy()

    def velocity(self) -> np.ndarray:
        """(Nn, 3) velocity (m/s)."""
        return self.dofmap.to_nodal(self.solver.v).copy()

    def acceleration(self) -> np.ndarray:
        """(Nn, 3) acceleration (m/s^2)."""
        return self.dofmap.to_nodal(self.solver.a).copy()

    def set_state(self, displacement: np.ndarray | None = None,
                  velocity: np.ndarray | None = None) -> None:
        """Set (Nn, 3) displacement (m) and velocity (m/s) (default zero; clamped nodes stay at
        zero) and recompute the acceleration from the current loads."""
        u = None if displacement is None else self.dofmap.to_dofs(displacement)
        v = None if velocity is None else self.dofmap.to_dofs(velocity)
        self.solver.initialize(u, v, self.external_force_dofs(), time=self.solver.time)

    # ------------------------------------------------------------------ loads
    def set_surface_forces(self, forces: np.ndarray) -> None:
        """Replace the contact forces (N), (Ns, 3), effective from the current time on.

        The current acceleration is updated with the change, so the central-difference steps
        that follow integrate the new load from their start: a load held over steps summing
        to T gives the structure exactly the impulse T x load (piecewise-constant loading).
        """
        old = self._surface_forces.copy()
        super().set_surface_forces(forces)
        change = np.zeros(self.dofmap.n_dofs)
        change[self._surface_dofs] = (self._surface_forces - old).ravel()
        change[self.solver.fixed] = 0.0
        self.solver.a += change / self.solver.m
        self.solver.f_ext = self.solver.f_ext + change

    # ------------------------------------------------------------------ checkpoint state
    def checkpoint_state(self) -> dict[str, np.ndarray | float]:
        """The solver state (:meth:`pdfem.fem.explicit.CentralDifference.checkpoint_state`) and the contact
        forces on the surface nodes (``surface_forces``, N), for a checkpoint."""
        out = self.solver.checkpoint_state()
        out["surface_forces"] = self._surface_forces.copy()
        return out

    def restore_state(self, state: dict) -> None:
        """Restore a state from :meth:`checkpoint_state` exactly."""
        forces = np.asarray(state["surface_forces"], dtype=np.float64)
        if forces.shape != self._surface_forces.shape:
            raise ValueError(f"surface_forces has shape {forces.shape}, expected "
                             f"{self._surface_forces.shape}")
        self.solver.restore_state(state)
        self._surface_forces[:] = forces

    # ------------------------------------------------------------------ surface interface
    def surface_points(self) -> np.ndarray:
        """(Ns, 3) current positions of the contact-surface nodes (m)."""
        return self._surface_points0 + self.solver.u[self._surface_dofs].reshape(-1, 3)

    def surface_velocities(self) -> np.ndarray:
        """(Ns, 3) current velocities of the contact-surface nodes (m/s)."""
        return self.solver.v[self._surface_dofs].reshape(-1, 3)

    # ------------------------------------------------------------------ time stepping
    def max_eigenvalue(self) -> float:
        """``omega_max^2`` (1/s^2) of the constrained ``M^-1 K`` (cached power iteration)."""
        return self.solver.max_eigenvalue()

    def stable_time_step(self) -> float:
        """Stable step (s): safety factor x 2 / omega_max (damping-reduced)."""
        return self.solver.stable_time_step()

    def critical_time_step(self) -> float:
        """Critical step (s) 2 / omega_max (damping-reduced), without the safety factor."""
        return self.solver.critical_time_step()

    def distribute(self, comm) -> None:
        """Share the integrator's solves over the ranks of ``comm`` (implicit steps: each rank
        solves its own independent parts, :meth:`pdfem.fem.implicit.Newmark.distribute`)."""
        self.solver.distribute(comm)

    def step(self, dt: float) -> None:
        """Advance by ``dt`` (s) under the current loads and accumulated contact forces.

        Raises
        ------
        InstabilityError
            If the displacement becomes NaN or infinite (a step above the stable step).
        """
        self.solver.step(dt, self.external_force_dofs(self.solver.time + dt))
        if not np.isfinite(self.solver.u).all():
            raise InstabilityError(
                f"structure '{self.name}': displacement became non-finite at t = "
                f"{self.solver.time:.6e} s; the step {dt:.3e} s exceeds the stable step "
                f"{self.stable_time_step():.3e} s or the loads are unbounded")

    # ------------------------------------------------------------------ results
    def kinetic_energy(self) -> float:
        """Kinetic energy 1/2 v.M v (J)."""
        return kinetic_energy(self.mass, self.solver.v)

    def momentum(self) -> np.ndarray:
        """(3,) linear momentum sum M v (kg m/s) with the lumped mass."""
        return self.dofmap.to_nodal(self.solver.m * self.solver.v).sum(axis=0)

    def strain_energy(self) -> float:
        """Strain energy 1/2 u.K u (J), with the integrator's K u."""
        return 0.5 * float(self.solver.u @ self.solver.stiffness_force())

    def stresses(self) -> np.ndarray:
        """(Ne, 3, 3) element stress tensors (Pa), at the element centres."""
        return element_stress(self.stress_basis, self.solver.u, self.material)

    def von_mises(self) -> np.ndarray:
        """(Ne,) von Mises stress per element (Pa)."""
        return von_mises(self.stresses())

    def nodal_von_mises(self) -> np.ndarray:
        """(Nn,) volume-weighted nodal average of the element von Mises stress (Pa)."""
        return nodal_average(self.mesh, self.von_mises(), self._volumes, self.cells)

    def probe(self, point) -> Probe:
        """A probe at ``point`` (m) (:func:`pdfem.fem.probe.make_probe`)."""
        return make_probe(self, point)

    def probe_values(self, probe: Probe) -> tuple[np.ndarray, float, np.ndarray]:
        """Displacement (m), von Mises stress and stress components (Pa) of a probe
        (:func:`pdfem.fem.probe.probe_values`)."""
        return probe_values(self, probe)

    def reaction(self, group: str) -> np.ndarray:
        """(3,) force (N) that the support at the named group exerts on the structure
        (``K u + C v + M a - f_ext`` summed over its nodes; 0 for the components it does not
        hold, :func:`pdfem.fem.supports.support_reaction`)."""
        return support_reaction(self.solver.residual_force(), self.dofmap,
                                self.group_nodes(group), self.supports.get(group, ()))

    # ------------------------------------------------------------------ run interface
    def output_mesh(self) -> tuple[np.ndarray, np.ndarray, str]:
        """Nodes (m), elements and their meshio cell type."""
        return self.points, self.cells, self.cell_type

    def output_fields(self) -> dict[str, np.ndarray]:
        """``u`` (Nn, 3) m, ``v`` (Nn, 3) m/s and ``von_mises`` (Ne,) Pa."""
        return {"u": self.displacement(), "v": self.velocity(), "von_mises": self.von_mises()}

    def frame_history(self) -> dict[str, float | np.ndarray]:
        """``kinetic``, ``strain`` (J) and ``reaction_<group>`` (N, (3,)) of each support
        (clamped or per component; components it does not hold are 0)."""
        hist = {"kinetic": self.kinetic_energy(), "strain": self.strain_energy()}
        for g, comps in self.supports.items():
            if g in self.fixed_groups or g in self._component_supports:
                hist[f"reaction_{g}"] = self.reaction(g)
        return hist

    def describe(self) -> str:
        """Nodes, DOFs, elements (which element) and critical step (or the implicit integrator)."""
        note = ("; the file's second-order elements were read by their corners and raised "
                "straight-sided" if self.mesh.file_order == 2 and not self.mesh.isoparametric
                else "; isoparametric (the file's midside nodes)" if self.mesh.isoparametric
                else "")
        dt_c = self.critical_time_step()
        step = (f"critical step {dt_c:.3e} s" if np.isfinite(dt_c)
                else "implicit Newmark steps (no stability limit)")
        return (f"structure '{self.name}': {self.n_nodes:,} nodes, {self.dofmap.n_dofs:,} DOFs, "
                f"{self.mesh.n_elements:,} {self.space.element_name}, {step}{note}")

    def check_mesh(self) -> None:
        """Refuse inverted or degenerate tetrahedra by their corners
        (:func:`pdfem.meshing.quality.check_cells`)."""
        if self.mesh.kind == "tet":
            check_cells(self.points, self.cells[:, :4], 3)

    def is_finite(self) -> bool:
        """Whether every displacement is finite."""
        return bool(np.isfinite(self.displacement()).all())

    # ------------------------------------------------------------------ contact impulses, energy
    def surface_inverse_mass(self) -> np.ndarray:
        """(Ns, 3) inverse lumped mass (1/kg) of the surface nodes; zero on supported DOFs."""
        dofs = self._surface_dofs
        return np.where(self.solver.free[dofs], 1.0 / self.solver.m[dofs], 0.0).reshape(-1, 3)

    def surface_motion(self):
        """Explicit: :class:`~pdfem.fem.surface_motion.PredictedSurface` (the structure steps
        after the contacts, which jump its velocity); implicit:
        :class:`~pdfem.fem.surface_motion.SteppedSurface` (it steps first, the contacts amend
        the step)."""
        return SteppedSurface(self) if self.implicit else PredictedSurface(self)

    def surface_compliance(self) -> LumpedCompliance | StepCompliance:
        """Explicit: :meth:`surface_inverse_mass` as a
        :class:`~pdfem.fem.step_compliance.LumpedCompliance`, kept. Implicit: the
        :class:`~pdfem.fem.step_compliance.StepCompliance` of the last step size, the blocks
        between nearby surface nodes of the mean displacement over a step per unit impulse,
        ``A^-1 / 2`` (1/kg, :meth:`pdfem.fem.implicit.Newmark.end_impulse`), by probing, once
        per step size; before the first step, the inverse masses."""
        dt = self.solver.last_dt
        if self._compliance is not None and (self._compliance[0] == dt or not self.implicit):
            return self._compliance[1]
        if not self.implicit or dt == 0.0:
            self._compliance = (dt, LumpedCompliance(self.surface_inverse_mass()))
            return self._compliance[1]
        mat = self.material
        points = self._surface_points0
        tri = self.surface_triangles
        spacing = float(np.max(np.linalg.norm(points[tri] - points[np.roll(tri, 1, axis=1)],
                                              axis=2))) if len(tri) else 0.0
        length = decay_length(wave_speed(mat.density, mat.youngs_modulus, mat.poisson_ratio),
                              dt, spacing)
        c = self.solver.compliance_blocks(dt, self._surface_dofs.reshape(-1, 3), points, length)
        self._compliance = (dt, StepCompliance(Coupling(c.start, c.index, 0.5 * c.blocks)))
        return self._compliance[1]

    def apply_surface_impulse(self, impulse: np.ndarray) -> float:
        """Give the surface nodes the impulses ((Ns, 3), N s); their work (J), zero on
        supports. Explicit: now, as a velocity jump, work ``v . J + J^2 / (2 m)``. Implicit: on
        the step just taken, as a force ramp to ``2 J / dt`` at its end
        (:meth:`pdfem.fem.implicit.Newmark.end_impulse`), work ``J . (u_new - u) / dt``."""
        return self.solver.contact_impulse(self._surface_dofs,
                                           np.asarray(impulse, dtype=np.float64).ravel())

    def applied_load(self) -> np.ndarray:
        """(3,) resultant (N) of the applied loads at the current time (contact excluded)."""
        return self.dofmap.to_nodal(self.solver.f_ext).sum(axis=0)

    def energy_terms(self) -> dict[str, float]:
        """Work of the loads and of moving supports, damping loss, kinetic correction (J)."""
        s = self.solver
        return {"load_work": s.work_external, "support_work": s.work_supports,
                "damping_dissipated": s.damping_dissipated,
                "kinetic_correction": s.kinetic_correction()}
