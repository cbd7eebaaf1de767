"""Applied loads of an elastic structure: nodal forces, surface tractions and pressures.

Forces on an :class:`pdfem.fem.structure.ElasticStructure` in a step are the sum of

- constant nodal forces (N) set with :meth:`AppliedLoads.set_nodal_forces`,
- surface tractions / pressures (Pa) added with :meth:`AppliedLoads.add_surface_load`
  (consistent nodal forces of the structure's elements, optionally scaled by a time history),
- surface-node forces (N) set with ``add_surface_forces``; they stay applied in every later
  step until ``clear_surface_forces``. (The coupled step gives the ice's contact impulses as
  velocity jumps, :meth:`pdfem.fem.base.Structure.apply_surface_impulse`, not as forces.)
"""

from __future__ import annotations

import numpy as np

from pdfem.fem.elasticity import surface_load


class AppliedLoads:
    """Load bookkeeping mixed into :class:`pdfem.fem.structure.ElasticStructure` (which sets
    ``_nodal_forces``, ``_pressure_dofs``, ``_load_dofs``, ``_timed_loads``, ``_surface_forces``,
    ``_surface_dofs``, ``dofmap``, ``space``, ``mesh``, ``solver``); SI units."""

    def set_nodal_forces(self, forces: np.ndarray) -> None:
        """Set constant external nodal forces (N), (Nn, 3) (replaces earlier ones)."""
        forces = np.asarray(forces, dtype=np.float64)
        if forces.shape != (self.n_nodes, 3):
            raise ValueError(f"nodal forces must have shape ({self.n_nodes}, 3), got "
                             f"{forces.shape}")
        self._nodal_forces = forces.copy()
        self._load_dofs = self.dofmap.to_dofs(self._nodal_forces) + self._pressure_dofs

    def add_surface_load(self, group: str, traction=(0.0, 0.0, 0.0), pressure: float = 0.0,
                         history=None) -> None:
        """Add a uniform traction (Pa, (3,)) and/or pressure (Pa, positive pushing into the
        structure) on a named surface group.

        ``history`` (optional) is a callable ``t -> factor`` (t in s) that scales this load in
        time, e.g. a pressure pulse; without it the load is constant.
        """
        f = surface_load(self.mesh, group, traction, pressure, self.space.element,
                         self.space.intorder)
        if history is not None:
            self._timed_loads.append((f, history))
            return
        self._pressure_dofs = self._pressure_dofs + f
        self._load_dofs = self._load_dofs + f

    def clear_loads(self) -> None:
        """Remove the nodal forces and surface loads (not the contact forces)."""
        self._nodal_forces = np.zeros((self.n_nodes, 3))
        self._pressure_dofs = np.zeros(self.dofmap.n_dofs)
        self._load_dofs = np.zeros(self.dofmap.n_dofs)
        self._timed_loads = []

    def external_force_dofs(self, time: float | None = None) -> np.ndarray:
        """(3 Nn,) total external force (N) at ``time`` (s; default the current time): loads
        (time histories evaluated at ``time``) plus the accumulated contact forces."""
        f = self._load_dofs.copy()
        t = self.solver.time if time is None else time
        for dofs, history in self._timed_loads:
            f += float(history(t)) * dofs
        f[self._surface_dofs] += self._surface_forces.ravel()
        return f
