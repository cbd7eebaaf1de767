"""Linear elasticity on a scikit-fem mesh: material, stiffness, lumped mass, surface loads.

Small-strain isotropic elasticity. :func:`vector_basis` gives the first-order elements,
``ElementVector(ElementTetP1())`` on tetrahedra and ``ElementVector(ElementHex1())`` on hexahedra
(2 x 2 x 2 Gauss points, which integrate the stiffness and the consistent mass of an undistorted
hexahedron exactly); the quadratic elements and their HRZ lumped mass, which a structure uses by
default, are in :mod:`pdfem.fem.fe_space`. The assembly functions here take any basis.

- stiffness ``K`` (N/m): ``int sigma(u) : eps(v) dV`` with ``sigma = lambda tr(eps) I + 2 mu eps``,
  assembled once into scipy CSR;
- lumped mass ``m`` (kg): row sums of the consistent mass ``int rho u . v dV``. For first-order
  elements every row sum is strictly positive (this is checked); it is not for P2 tetrahedra
  or serendipity hexahedra, which use HRZ lumping (:func:`pdfem.fem.fe_space.hrz_mass`);
- surface loads: a traction (Pa) or a pressure (Pa, positive pushing into the body) on a named
  surface group, integrated consistently into nodal forces (N).

Vectors over degrees of freedom (DOFs) follow scikit-fem's order, which :class:`DofMap` reads
from ``basis.nodal_dofs`` (for ``ElementVector`` it is interleaved: node k owns DOFs 3k, 3k+1,
3k+2). Use :meth:`DofMap.to_dofs` / :meth:`DofMap.to_nodal` rather than assuming it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import skfem

from pdfem.fem.assembly import assemble, assemble_vector, elasticity_matrices, local_values
from pdfem.fem.mesh import FEMesh

STEEL_DEFAULTS: dict[str, float] = {
    "density": 7850.0,         # kg/m^3, structural steel (pdfem design notes)
    "youngs_modulus": 210e9,   # Pa
    "poisson_ratio": 0.3,      # -
}


@dataclass(frozen=True)
class ElasticMaterial:
    """Isotropic linear-elastic material (SI).

    Parameters
    ----------
    density
        Mass density rho (kg/m^3), > 0.
    youngs_modulus
        Young's modulus E (Pa), > 0.
    poisson_ratio
        Poisson's ratio nu, -1 < nu < 0.5.

    Raises
    ------
    ValueError
        If a value is out of range or not finite.
    """

    density: float = STEEL_DEFAULTS["density"]
    youngs_modulus: float = STEEL_DEFAULTS["youngs_modulus"]
    poisson_ratio: float = STEEL_DEFAULTS["poisson_ratio"]

    def __post_init__(self) -> None:
        for name in ("density", "youngs_modulus"):
            val = float(getattr(self, name))
            if not (math.isfinite(val) and val > 0.0):
                raise ValueError(f"{name} must be positive and finite (got {val!r})")
        nu = float(self.poisson_ratio)
        if not (math.isfinite(nu) and -1.0 < nu < 0.5):
            raise ValueError(f"poisson_ratio must lie in (-1, 0.5) (got {nu!r})")

    @property
    def lame(self) -> tuple[float, float]:
        """Lame constants (lambda, mu) in Pa."""
        E, nu = self.youngs_modulus, self.poisson_ratio
        return E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))

    @property
    def shear_modulus(self) -> float:
        """Shear modulus G = E / (2 (1 + nu)) (Pa)."""
        return self.lame[1]


class DofMap:
    """Conversion between (Nn, 3) nodal arrays and DOF vectors in scikit-fem's order.

    Parameters
    ----------
    nodal_dofs
        (3, Nn) DOF index of component c at node k (``basis.nodal_dofs``).
    """

    def __init__(self, nodal_dofs: np.ndarray):
        nodal_dofs = np.asarray(nodal_dofs, dtype=np.int64)
        if nodal_dofs.ndim != 2 or nodal_dofs.shape[0] != 3:
            raise ValueError(f"nodal_dofs must have shape (3, Nn), got {nodal_dofs.shape}")
        self.nodal_dofs = nodal_dofs
        self.n_nodes = nodal_dofs.shape[1]
        self.n_dofs = 3 * self.n_nodes
        #: node-major (Nn, 3) -> DOF index; ``vec[order] = arr.ravel()``.
        self.order = np.ascontiguousarray(nodal_dofs.T).ravel()
        self.interleaved = bool(np.array_equal(self.order, np.arange(self.n_dofs)))

    def to_dofs(self, nodal: np.ndarray) -> np.ndarray:
        """(Nn, 3) nodal array -> (3 Nn,) DOF vector (a view when the order is interleaved)."""
        nodal = np.asarray(nodal, dtype=np.float64)
        if nodal.shape != (self.n_nodes, 3):
            raise ValueError(f"expected a ({self.n_nodes}, 3) array, got {nodal.shape}")
        if self.interleaved:
            return np.ascontiguousarray(nodal).reshape(-1)
        out = np.empty(self.n_dofs)
        out[self.order] = nodal.ravel()
        return out

    def to_nodal(self, dofs: np.ndarray) -> np.ndarray:
        """(3 Nn,) DOF vector -> (Nn, 3) nodal array (a view when the order is interleaved)."""
        dofs = np.asarray(dofs)
        if dofs.shape != (self.n_dofs,):
            raise ValueError(f"expected a ({self.n_dofs},) vector, got {dofs.shape}")
        if self.interleaved:
            return dofs.reshape(self.n_nodes, 3)
        return dofs[self.order].reshape(self.n_nodes, 3)

    def dofs_of(self, nodes: np.ndarray, components: tuple[int, ...] = (0, 1, 2)) -> np.ndarray:
        """Sorted int64 DOF indices of the given components (0 = x, 1 = y, 2 = z) at ``nodes``."""
        nodes = np.asarray(nodes, dtype=np.int64)
        return np.sort(self.nodal_dofs[list(components)][:, nodes].ravel())


def element_for(mesh: FEMesh) -> skfem.ElementVector:
    """The vector element of a mesh: P1 tetrahedron or trilinear hexahedron."""
    if mesh.kind == "tet":
        return skfem.ElementVector(skfem.ElementTetP1())
    if mesh.kind == "hex":
        return skfem.ElementVector(skfem.ElementHex1())
    raise ValueError(f"unknown mesh kind {mesh.kind!r}; expected 'tet' or 'hex'")


def _intorder(mesh: FEMesh) -> int:
    # tets: mass integrand is quadratic; hexes: 2-point Gauss per direction (exact for affine).
    return 2 if mesh.kind == "tet" else 3


def vector_basis(mesh: FEMesh) -> skfem.CellBasis:
    """scikit-fem basis of the vector element over the whole mesh."""
    return skfem.Basis(mesh.mesh, element_for(mesh), intorder=_intorder(mesh))


def stiffness_matrix(basis: skfem.CellBasis, material: ElasticMaterial) -> sp.csr_matrix:
    """Stiffness matrix K (N/m), symmetric, scipy CSR in the basis' DOF order (assembled
    element by element, vectorised: :mod:`pdfem.fem.assembly`)."""
    return assemble(basis, elasticity_matrices(*material.lame))


def lumped_mass(basis: skfem.CellBasis, density: float) -> np.ndarray:
    """Row-sum lumped mass (kg) per DOF, (3 Nn,), every entry strictly positive.

    Raises
    ------
    ValueError
        If a lumped mass is not strictly positive (a node without elements, or an element type
        whose row-sum lumping fails, such as P2 tetrahedra).
    """
    phi = local_values(basis)                                        # (nloc, 3, Ne, nq)
    # row sum of the consistent mass int rho phi_a . phi_b dV over the element's b
    rows = float(density) * np.einsum("acen,cen,en->ae", phi, phi.sum(axis=0), basis.dx)
    m = assemble_vector(basis, rows)
    if not np.all(m > 0.0):
        bad = int(np.sum(~(m > 0.0)))
        raise ValueError(f"row-sum lumped mass has {bad} non-positive entries (min {m.min():.3e} "
                         "kg); use first-order elements and a mesh without unused nodes")
    return m


def element_volumes(mesh: FEMesh) -> np.ndarray:
    """Volume (m^3) of every element, (Ne,)."""
    basis = skfem.Basis(mesh.mesh, element_for(mesh).elem, intorder=_intorder(mesh))
    return basis.dx.sum(axis=1)


def surface_load(mesh: FEMesh, group: str, traction=(0.0, 0.0, 0.0),
                 pressure: float = 0.0, element: skfem.Element | None = None,
                 intorder: int | None = None) -> np.ndarray:
    """Consistent nodal forces (N) of a uniform surface load on a named surface group.

    Parameters
    ----------
    mesh
        The mesh with the surface group.
    group
        Name of a surface (2-D) physical group of boundary faces.
    traction
        (3,) traction vector t (Pa) acting on the surface.
    pressure
        Pressure p (Pa), positive pushing into the body (adds ``-p n``, n the outward normal).
    element, intorder
        Vector element and Gauss order (default: the first-order ones of :func:`vector_basis`).

    Returns
    -------
    numpy.ndarray
        (3 Nn,) force vector in the DOF order of a basis of ``element``.
    """
    facets = mesh.group_facet_indices(group)
    fb = skfem.FacetBasis(mesh.mesh, element or element_for(mesh), facets=facets,
                          intorder=intorder or _intorder(mesh))
    t = np.asarray(traction, dtype=np.float64).reshape(3)
    p = float(pressure)

    @skfem.LinearForm
    def load(v, w):
        n = w.n
        return (t[0] - p * n[0]) * v[0] + (t[1] - p * n[1]) * v[1] + (t[2] - p * n[2]) * v[2]

    return skfem.asm(load, fb)
