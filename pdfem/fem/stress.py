"""Stress recovery, energies and support reactions of a linear-elastic FE model.

- element stress (Pa): ``sigma = lambda tr(eps) I + 2 mu eps`` from the displacement gradient at
  the element centre (exact and constant for P1 tetrahedra; the centre value for hexahedra and
  for the quadratic elements);
- von Mises stress (Pa) per element, and volume-weighted nodal averages for output;
- strain energy ``1/2 u . K u`` and kinetic energy ``1/2 v . M v`` (J) with the lumped mass;
- the reaction (N) at a support: ``K u + C v + M a - f_ext`` summed over the support's DOFs, i.e.
  the force the support exerts on the structure.
"""

from __future__ import annotations

import numpy as np
import skfem

from pdfem.fem.elasticity import DofMap, ElasticMaterial, element_for
from pdfem.fem.mesh import FEMesh

_CENTRE = {"tet": (0.25, 0.25, 0.25), "hex": (0.5, 0.5, 0.5)}


def centre_basis(mesh: FEMesh, element: skfem.Element | None = None) -> skfem.CellBasis:
    """Vector basis of ``element`` (default: first order, :func:`element_for`) with one
    evaluation point at each element's centre (for stresses)."""
    X = np.array(_CENTRE[mesh.kind], dtype=np.float64).reshape(3, 1)
    return skfem.Basis(mesh.mesh, element or element_for(mesh), quadrature=(X, np.ones(1)))


def hooke_stress(grad: np.ndarray, material: ElasticMaterial) -> np.ndarray:
    """Cauchy stress (Pa) of the linear isotropic material from a displacement gradient.

    Parameters
    ----------
    grad
        (3, 3, ...) ``du_i / dx_j`` (any trailing axes: elements, points).
    material
        The elastic material (its Lame constants).

    Returns
    -------
    numpy.ndarray
        (3, 3, ...) ``2 mu eps + lam tr(eps) I``, ``eps`` the symmetric part of ``grad``.
    """
    eps = 0.5 * (grad + np.swapaxes(grad, 0, 1))
    lam, mu = material.lame
    tr = eps[0, 0] + eps[1, 1] + eps[2, 2]
    sigma = 2.0 * mu * eps
    for i in range(3):
        sigma[i, i] += lam * tr
    return sigma


def element_stress(basis: skfem.CellBasis, u: np.ndarray, material: ElasticMaterial) -> np.ndarray:
    """Cauchy stress (Pa) per element at the evaluation point of ``basis``.

    Parameters
    ----------
    basis
        A :func:`centre_basis` (one point per element).
    u
        Displacement DOF vector (m) in the basis' DOF order.
    material
        The elastic material.

    Returns
    -------
    numpy.ndarray
        (Ne, 3, 3) symmetric stress tensors.
    """
    grad = basis.interpolate(u).grad[:, :, :, 0]          # (3, 3, Ne): du_i / dx_j
    return np.ascontiguousarray(hooke_stress(grad, material).transpose(2, 0, 1))


def von_mises(sigma: np.ndarray) -> np.ndarray:
    """von Mises equivalent stress ``sqrt(3/2 s:s)`` (Pa) of (..., 3, 3) stress tensors."""
    tr = np.trace(sigma, axis1=-2, axis2=-1)
    s = sigma - tr[..., None, None] / 3.0 * np.eye(3)
    return np.sqrt(1.5 * np.einsum("...ij,...ij->...", s, s))


def nodal_average(mesh: FEMesh, values: np.ndarray, volumes: np.ndarray,
                  cells: np.ndarray | None = None) -> np.ndarray:
    """Volume-weighted average at the nodes of a per-element field.

    Parameters
    ----------
    mesh
        The mesh.
    values
        (Ne, ...) element values.
    volumes
        (Ne,) element volumes (m^3), the weights.
    cells
        (Ne, k) connectivity over FE nodes (default: the mesh's corners), e.g. with midside
        nodes; the result has one row per node ``0 .. cells.max()``.

    Returns
    -------
    numpy.ndarray
        (Nn, ...) averages over the elements around each node.
    """
    values = np.asarray(values, dtype=np.float64)
    t = mesh.mesh.t if cells is None else np.asarray(cells).T     # (k, Ne)
    k, ne = t.shape
    n_nodes = mesh.n_nodes if cells is None else int(t.max()) + 1
    flat = values.reshape(ne, -1)
    idx = t.T.ravel()
    w = np.repeat(volumes, k)
    num = np.zeros((n_nodes, flat.shape[1]))
    for c in range(flat.shape[1]):
        num[:, c] = np.bincount(idx, weights=w * np.repeat(flat[:, c], k), minlength=n_nodes)
    den = np.bincount(idx, weights=w, minlength=n_nodes)
    return (num / den[:, None]).reshape((n_nodes,) + values.shape[1:])


def strain_energy(stiffness, u: np.ndarray) -> float:
    """Strain energy ``1/2 u . K u`` (J); ``stiffness`` a scipy sparse matrix or anything
    with its ``@`` (e.g. :class:`pdfem.fem.node_blocks.NodeBlockOperator`)."""
    return 0.5 * float(u @ (stiffness @ u))


def kinetic_energy(mass: np.ndarray, v: np.ndarray) -> float:
    """Kinetic energy ``1/2 v . M v`` (J) with the lumped mass vector."""
    return 0.5 * float(np.dot(mass * v, v))


def reaction_force(residual: np.ndarray, dofmap: DofMap, nodes: np.ndarray) -> np.ndarray:
    """Total reaction (N) at a set of supported nodes.

    Parameters
    ----------
    residual
        ``K u + C v + M a - f_ext`` per DOF (N), e.g.
        :meth:`pdfem.fem.explicit.CentralDifference.residual_force`, or ``K u - f_ext`` of a
        static solution.
    dofmap
        DOF order of ``residual``.
    nodes
        Node indices of the support.

    Returns
    -------
    numpy.ndarray
        (3,) force the support exerts on the structure.
    """
    return dofmap.to_nodal(residual)[np.asarray(nodes, dtype=np.int64)].sum(axis=0)
