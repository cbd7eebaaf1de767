"""The LPS kernels in one namespace: the public functions of the kernel modules, re-exported.

The kernels live in modules with one concept each:

- :mod:`pdfem.pd.bonds.workspace`: chunk layout and overflow buffers of the race-free, deterministic
  parallel pair loops (:class:`PairWorkspace`; the numba side in :mod:`pdfem.pd.bonds.chunk_kernels`);
- :mod:`pdfem.pd.bonds.influence`: bond weights omega = w beta (influence function times partial-volume
  factor), with the cubic-lattice isotropy correction;
- :mod:`pdfem.pd.bonds.lps_law`: the LPS force law per bond (stretch, dilatation term, force-state
  scalar, breaking test), written once and inlined into every loop below;
- :mod:`pdfem.pd.bonds.pair_loop`: the particle-pair loops' public functions (weighted volume,
  dilatation, forces and bond breaking, the fused step) and :mod:`pdfem.pd.bonds.pair_sums` (strain
  energy, the potential of crushed bonds, damage), over the numba loops of
  :mod:`pdfem.pd.bonds.pair_step_kernels` and :mod:`pdfem.pd.bonds.pair_sum_kernels`;
- :mod:`pdfem.pd.bonds.family_kernels`: the per-particle full-family reference loops;
- :mod:`pdfem.pd.failure.fracture_kernels`: the strain energy released by the bonds broken in a step
  (used by :mod:`pdfem.pd.failure.fracture`);
- :mod:`pdfem.pd.integrate`: the velocity-Verlet kick and drift;
- :mod:`pdfem.pd.timestep`: stable time steps.

``from pdfem.pd.bonds import kernels as kn`` gives all of them as ``kn.<name>``.
"""

from __future__ import annotations

from pdfem.pd.bonds.family import dilatation_family, forces_family
from pdfem.pd.bonds.influence import bond_weights, isotropy_gain
from pdfem.pd.integrate import verlet_drift, verlet_kick
from pdfem.pd.bonds.pair_loop import (
    SIGNED,
    broken_flags,
    dilatation,
    dilatation_and_forces,
    family_sum,
    forces,
    signed_weights,
    weighted_volume,
)
from pdfem.pd.bonds.pair_sums import contact_bond_energy, damage, strain_energy
from pdfem.pd.timestep import max_eigenvalue_time_step, stable_time_step
from pdfem.pd.bonds.workspace import SERIAL_BELOW_PAIRS, SERIAL_BELOW_PARTICLES, PairWorkspace

__all__ = [
    "SERIAL_BELOW_PAIRS",
    "SERIAL_BELOW_PARTICLES",
    "SIGNED",
    "PairWorkspace",
    "broken_flags",
    "bond_weights",
    "contact_bond_energy",
    "damage",
    "dilatation",
    "dilatation_and_forces",
    "dilatation_family",
    "family_sum",
    "forces",
    "forces_family",
    "isotropy_gain",
    "max_eigenvalue_time_step",
    "signed_weights",
    "stable_time_step",
    "strain_energy",
    "verlet_drift",
    "verlet_kick",
    "weighted_volume",
]
