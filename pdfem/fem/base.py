"""The structure interface: what the coupler and the driver need from any structure.

A structure is a body with a contact surface (:class:`pdfem.fem.surface.SurfaceBody`: surface
nodes, triangles, the contact forces it receives) that advances in time under those forces.
:class:`Structure` adds what a run needs from it: its stable-step limit, output (mesh, fields
per frame, a history row per frame), energies, how the work of the contact loads on it counts in
the energy balance, a mesh check, checkpoints, and a line for the start-up report. The driver
calls only these methods, so it never asks which kind of structure it holds.

Implementations: :class:`pdfem.fem.structure.ElasticStructure` (linear-elastic FE, explicit)
and :class:`pdfem.motion.rigid.RigidBody` (prescribed rigid motion) and
:class:`pdfem.motion.ship.Ship` (a free-floating rigid hull).

Adding a kind
-------------
Write one new file in :mod:`pdfem.fem` with a subclass of :class:`Structure`, and add one line
to :data:`pdfem.run.build_structures.STRUCTURE_KINDS` mapping the case's ``kind`` to a builder
``(config, mesh path, case file) -> Structure`` (a classmethod of the new class, or a small
function beside the registry). Override what differs from the defaults below: a structure
without elastic energy, step limit or mesh checks inherits zeros, ``inf`` and no check.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from pdfem.fem.step_compliance import LumpedCompliance, StepCompliance
from pdfem.fem.surface import SurfaceBody
from pdfem.fem.surface_motion import PredictedSurface


ENERGY_TERMS = ("load_work", "support_work", "damping_dissipated", "kinetic_correction")
"""Keys of :meth:`Structure.energy_terms`."""


class Structure(SurfaceBody, ABC):
    """A structure in a coupled run (SI units: m, s, N, J, Pa)."""

    name: str

    prescribed_motion: bool = False
    """True when the structure moves as prescribed, whatever the loads (a rigid indenter): the
    work of the contact loads on it is then energy supplied to the ice from outside (the energy
    balance's ``rigid_body_work``), not energy the structure stores. False for a structure that
    responds to its loads."""

    def surface_motion(self):
        """How the contact surface moves over the substeps of a coupled step
        (:mod:`pdfem.fem.surface_motion`): by default predicted from the structure's state,
        the structure stepping after the contacts; a prescribed motion returns a
        :class:`~pdfem.fem.surface_motion.PrescribedSurface`."""
        return PredictedSurface(self)

    shaft = None
    """Shaft and blade loads of a rotating structure (:mod:`pdfem.motion.shaft_loads`), else None."""

    # -- time stepping -------------------------------------------------------------------------
    @abstractmethod
    def step(self, dt: float) -> None:
        """Advance by ``dt`` (s) under the current loads and contact forces."""

    def critical_time_step(self) -> float:
        """Stable-step limit (s) of the explicit integration, no safety factor; ``inf`` if none."""
        return math.inf

    def distribute(self, comm) -> None:
        """Share the structure's own work over the ranks of ``comm``
        (:mod:`pdfem.parallel.comm`). Every rank holds the structure's whole state and steps it;
        what a structure can split without changing a bit of that state it splits here (the
        implicit steps' solves, :meth:`pdfem.fem.implicit.Newmark.distribute`). Default:
        nothing to share, every rank does all of it."""

    def stable_time_step(self) -> float:
        """Largest stable step (s) with the structure's own safety factor; ``inf`` if none."""
        return math.inf

    # -- contact impulses ----------------------------------------------------------------------
    def surface_rotation(self) -> np.ndarray | None:
        """(3, 3) rotation of the contact surface from its reference configuration, when the
        surface moves as a rigid body (its normals are then the reference ones rotated, not
        recomputed); ``None`` when it deforms. Default: ``None``."""
        return None

    def surface_inverse_mass(self) -> np.ndarray:
        """(Ns, 3) inverse lumped mass (1/kg) of each contact-surface node and component; zero
        where the motion is prescribed (supports, a prescribed-motion body), which the contact
        treats as infinitely heavy. Default: zeros."""
        return np.zeros((self.n_surface_nodes, 3))

    _kept_compliance: LumpedCompliance | None = None

    def surface_compliance(self) -> LumpedCompliance | StepCompliance:
        """How far the contact surface gives way per unit impulse over the coming contact
        (1/kg, :mod:`pdfem.fem.step_compliance`): the lumped inverse masses of the nodes, or an
        implicit structure's coupled step compliance (its nodes move together over a step).
        The contact reads it at every substep and takes it anew only when handed another
        object. Default: :meth:`surface_inverse_mass` of the first call, kept."""
        if self._kept_compliance is None:
            self._kept_compliance = LumpedCompliance(self.surface_inverse_mass())
        return self._kept_compliance

    def apply_surface_impulse(self, impulse: np.ndarray) -> float:
        """Give the contact-surface nodes the impulses ``impulse`` ((Ns, 3), N s) now, as a jump
        of their velocity (an implicit structure: as an amendment of the step just taken,
        :meth:`pdfem.fem.implicit.Newmark.end_impulse`); return the work they did (J: the
        kinetic-energy change ``v . J + J^2 / (2 m)``; implicit: ``J . (u_new - u) / dt``).
        Default: nothing, 0 (a prescribed motion does not respond; the caller books the work
        its drive does)."""
        return 0.0

    # -- output --------------------------------------------------------------------------------
    @abstractmethod
    def output_mesh(self) -> tuple[np.ndarray, np.ndarray, str]:
        """``(points (m), cells, meshio cell type)`` of the mesh that output fields live on."""

    @abstractmethod
    def output_fields(self) -> dict[str, np.ndarray]:
        """Fields of one output frame on :meth:`output_mesh`: at least ``u`` (nodal
        displacement, m); ``von_mises`` (Pa) per cell where the structure has stresses."""

    def frame_history(self) -> dict[str, float | np.ndarray]:
        """One history row per output frame (energies J, support reactions N); empty: none."""
        return {}

    def motion_history(self) -> dict[str, float | np.ndarray]:
        """One row of rigid-body motion every coupling step (a free ship: position, rotation,
        velocities); empty: none."""
        return {}

    def surface_groups(self) -> dict[str, np.ndarray]:
        """``{patch name: (T,) bool}`` over the contact triangles: the load patches whose force
        histories the run writes (:mod:`pdfem.coupling.facet_loads`); empty: none."""
        return {}

    def describe(self) -> str:
        """One line for the start-up report."""
        return f"structure '{self.name}'"

    # -- energy balance ------------------------------------------------------------------------
    def kinetic_energy(self) -> float:
        """Kinetic energy (J) the structure holds (0 for a prescribed motion)."""
        return 0.0

    def strain_energy(self) -> float:
        """Elastic energy (J) the structure holds (0 for a rigid body)."""
        return 0.0

    def potential_energy(self) -> float:
        """Potential energy (J) of the structure in fields it moves through (a floating ship:
        gravity and hydrostatics); 0 by default."""
        return 0.0

    def applied_load(self) -> np.ndarray:
        """(3,) resultant (N) of the loads applied to the structure now (pressures, tractions,
        nodal forces; not the contact). Default: zero."""
        return np.zeros(3)

    def energy_terms(self) -> dict[str, float]:
        """Energy terms (J) the structure keeps itself since the start: ``load_work`` (work of
        its applied loads), ``support_work`` (of its supports that move), ``damping_dissipated``
        (taken by its damping) and ``kinetic_correction`` (the time integrator's share of the
        kinetic energy, :meth:`pdfem.fem.explicit.CentralDifference.kinetic_correction`).
        Default: all zero."""
        return dict.fromkeys(ENERGY_TERMS, 0.0)

    # -- checks --------------------------------------------------------------------------------
    def check_mesh(self) -> None:
        """Raise :class:`pdfem.meshing.quality.MeshQualityError` for a mesh the structure cannot
        be run on (inverted or degenerate elements); nothing to check by default."""

    def is_finite(self) -> bool:
        """Whether the state is finite (after a blow-up, to decide on a last frame)."""
        return True

    # -- checkpoints ---------------------------------------------------------------------------
    @abstractmethod
    def checkpoint_state(self) -> dict[str, np.ndarray | float]:
        """Copies of the state a restart needs."""

    @abstractmethod
    def restore_state(self, state: dict) -> None:
        """Put a state from :meth:`checkpoint_state` back, exactly."""
