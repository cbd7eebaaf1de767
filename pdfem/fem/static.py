"""Linear static displacement of an elastic structure under its constant loads.

Solves ``K u = f`` on the free DOFs (the supports' Dirichlet DOFs removed, held at zero) by a
sparse LU factorisation (:func:`scipy.sparse.linalg.spsolve`), with ``f`` the structure's
external force at t = 0 (nodal forces and surface loads; time-history loads at their t = 0
factor). Used to check plate deflections against plate theory. SI units: u in m, f in N.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve

if TYPE_CHECKING:
    from pdfem.fem.structure import ElasticStructure


def static_displacement(structure: ElasticStructure,
                        force: np.ndarray | None = None,
                        stiffness: sp.spmatrix | None = None) -> np.ndarray:
    """(Nn, 3) static displacement (m) of ``structure`` under its loads.

    Parameters
    ----------
    structure
        The elastic structure (``K``, ``solver.free``, ``dofmap``).
    force
        (3 Nn,) DOF force vector (N) to use instead of ``structure.external_force_dofs(0.0)``.
    stiffness
        (3 Nn, 3 Nn) stiffness (N/m) to use instead of ``structure.K`` (e.g. a spinning
        structure's, :meth:`pdfem.motion.frame_structure.FrameStructure.rotating_stiffness`).

    Returns
    -------
    numpy.ndarray
        The nodal displacement, zero at the supports.

    Raises
    ------
    ValueError
        If the supports leave the structure free to move as a rigid body (singular K).
    """
    f = structure.external_force_dofs(0.0) if force is None else np.asarray(force, np.float64)
    free = structure.solver.free
    k = sp.csc_matrix(sp.csr_matrix(structure.K if stiffness is None else stiffness)
                      [free][:, free])
    with np.errstate(all="ignore"):
        u_free = spsolve(k, f[free])
    if not np.all(np.isfinite(u_free)):
        raise ValueError(f"structure '{structure.name}': its supports do not hold it (the "
                         "stiffness on the free DOFs is singular); add fixed groups or supports")
    u = np.zeros(structure.dofmap.n_dofs)
    u[free] = u_free
    return structure.dofmap.to_nodal(u).copy()
