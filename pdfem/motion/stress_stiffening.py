"""Stress (geometric) stiffening of a spinning elastic structure: the stiffness K_sigma that the
centrifugal prestress adds (docs/rotating_structures.md).

Linear elasticity has no stiffness from a prestress; the bending frequencies of a spinning
blade rise with speed (Southwell) because of it. Here the prestress sigma0 is the linear static
stress under the centrifugal load at full speed on the reference geometry (supports held), and

    K_sigma[a i, b i] = int sigma0_jk  dN_a/dx_j  dN_b/dx_k  dV      (each component i),

the usual initial-stress matrix (e.g. Cook, Malkus, Plesha & Witt, *Concepts and Applications
of Finite Element Analysis*, 4th ed., 2002, ch. 18). At speed factor s(t) it is s^2 K_sigma
(the prestress grows with omega^2). SI units: Pa, N/m.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp

from pdfem.fem.assembly import assemble, initial_stress_matrices
from pdfem.fem.static import static_displacement
from pdfem.fem.stress import hooke_stress
from pdfem.geometry.vectors import cross

if TYPE_CHECKING:
    from pdfem.motion.moving_frame import MovingFrame
    from pdfem.fem.structure import ElasticStructure


def prestress(structure: ElasticStructure, force: np.ndarray) -> np.ndarray:
    """(3, 3, Ne, Nq) linear static stress (Pa) at the quadrature points of the structure's
    basis under the DOF force vector ``force`` (N), its supports held."""
    u = structure.dofmap.to_dofs(static_displacement(structure, force))
    return hooke_stress(structure.basis.interpolate(u).grad, structure.material)


def centrifugal_stiffness(structure: ElasticStructure, frame: MovingFrame,
                          r: np.ndarray, node_mass: np.ndarray) -> sp.csr_matrix:
    """K_sigma (N/m, DOF order) of the centrifugal prestress at the frame's full speed.

    Parameters
    ----------
    structure
        The elastic structure (basis, supports, material).
    frame
        Its frame; only the final angular velocity matters.
    r
        (Nn, 3) reference positions relative to the frame's centre (m).
    node_mass
        (Nn,) lumped nodal masses (kg).
    """
    w = np.asarray(frame.angular_velocity, dtype=np.float64)
    f = -node_mass[:, None] * cross(w, cross(w, r))
    sigma = prestress(structure, structure.dofmap.to_dofs(f))
    return assemble(structure.basis, initial_stress_matrices(sigma))
