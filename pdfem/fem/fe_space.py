"""The finite-element space of an elastic structure: element choice, FE nodes, HRZ lumped mass.

Element choice (docs/structures_convergence.md): first-order tetrahedra and hexahedra lock in
bending, so by default (``order = 2``) a tetrahedral mesh gets 10-node tetrahedra
(``ElementTetP2``) and a hexahedral mesh 20-node serendipity hexahedra (``ElementHexS2``),
built by scikit-fem on the corner mesh (edge-midpoint DOFs, straight-sided elements). Full
integration: Gauss order 4 for the quadratic elements (exact mass of an affine element); the
first-order elements (``order = 1``: ``ElementTetP1`` / ``ElementHex1``) keep orders 2 / 3.

On an isoparametric mesh (a tetra10 file, :class:`skfem.MeshTet2`) the elements keep the
file's curved geometry and the midside nodes sit at the file's positions.

FE nodes are every DOF location: the mesh vertices (same indices as in the mesh), then one node
per edge, then per facet and per element where the element has DOFs there. :class:`FESpace`
gives their positions (m), the (3, N) DOF table for :class:`pdfem.fem.elasticity.DofMap`, the
cells in meshio / VTK node order for output (``tetra10``, ``hexahedron20``), the FE nodes of a
named group (midside nodes on the group's edges, faces and elements included) and the contact
faces split into linear triangles over all face nodes.

HRZ lumping (Hinton, Rock & Zienkiewicz 1976, Earthquake Eng. Struct. Dyn. 4): per element and
direction ``m_ii = M_ii m_e / sum_j M_jj``, with ``M_ii`` the consistent mass diagonal and
``m_e`` the element mass; every entry is strictly positive for these elements (row sums are
not, for TetP2 and HexS2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import skfem
from skfem.io.meshio import HEX_MAPPING

from pdfem.fem.assembly import assemble_vector, local_values
from pdfem.fem.mesh import FEMesh
from pdfem.fem.mesh_second_order import edge_lookup

#: mesh kind -> order -> (scalar element class, Gauss order, meshio cell type)
ELEMENTS = {
    "tet": {1: (skfem.ElementTetP1, 2, "tetra"), 2: (skfem.ElementTetP2, 4, "tetra10")},
    "hex": {1: (skfem.ElementHex1, 3, "hexahedron"), 2: (skfem.ElementHexS2, 4, "hexahedron20")},
}
ELEMENT_NAMES = {"tetra": "4-node tetrahedra (TetP1)", "tetra10": "10-node tetrahedra (TetP2)",
                 "hexahedron": "8-node hexahedra (Hex1)",
                 "hexahedron20": "20-node serendipity hexahedra (HexS2)"}

# VTK corner pairs of the midside nodes: tetra10 (nodes 4-9) and hexahedron20 (nodes 8-19).
_VTK_EDGES = {
    "tet": [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)],
    "hex": [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
            (0, 4), (1, 5), (2, 6), (3, 7)],
}


@dataclass
class FESpace:
    """The vector FE space of a mesh (see the module docstring); SI units (m).

    Attributes
    ----------
    mesh
        The corner mesh with its named groups.
    order
        1 or 2.
    cell_type
        meshio cell type of the elements (``tetra``, ``tetra10``, ``hexahedron``,
        ``hexahedron20``).
    basis
        scikit-fem vector basis over all elements.
    nodal_dofs
        (3, Nfe) DOF of component c at FE node k.
    points
        (Nfe, 3) FE node positions (m).
    node_of_dof
        (Ndofs,) FE node of each DOF.
    """

    mesh: FEMesh
    order: int
    cell_type: str
    intorder: int
    basis: skfem.CellBasis
    nodal_dofs: np.ndarray
    points: np.ndarray
    node_of_dof: np.ndarray

    @property
    def element(self) -> skfem.ElementVector:
        """The vector element."""
        return self.basis.elem

    @property
    def n_nodes(self) -> int:
        """Number of FE nodes."""
        return self.points.shape[0]

    @property
    def element_name(self) -> str:
        """Human-readable element name, e.g. ``20-node serendipity hexahedra (HexS2)``."""
        return ELEMENT_NAMES[self.cell_type]

    def edge_nodes(self, pairs: np.ndarray) -> np.ndarray:
        """FE node on the mesh edge between each corner pair of ``pairs`` (..., 2) (order 2)."""
        m = self.mesh.mesh
        e = edge_lookup(m.edges, m.nvertices, pairs)
        if (e < 0).any():
            raise ValueError("a corner pair is not an edge of the mesh")
        return self.node_of_dof[self.basis.edge_dofs[0, e]]

    def cells(self) -> np.ndarray:
        """(Ne, k) int32 connectivity over FE nodes in meshio / VTK node order."""
        t = self.mesh.mesh.t
        corners = t[HEX_MAPPING[:8]] if self.mesh.kind == "hex" else t
        corners = corners.T.astype(np.int64)
        if self.order == 1:
            return np.ascontiguousarray(corners, dtype=np.int32)
        pairs = np.stack([corners[:, list(p)] for p in _VTK_EDGES[self.mesh.kind]], axis=1)
        return np.ascontiguousarray(np.hstack([corners, self.edge_nodes(pairs)]), dtype=np.int32)

    def group_nodes(self, name: str) -> np.ndarray:
        """Sorted int32 FE nodes of a named group: its mesh nodes and, for order 2, the midside
        nodes on its edges (line groups), faces (surface groups) and elements (volume groups).

        Raises
        ------
        ValueError
            If the mesh has no group of that name.
        """
        nodes = [self.mesh.group_nodes(name).astype(np.int64)]
        if self.order > 1:
            if name in self.mesh.element_sets:
                dofs = self.basis.element_dofs[:, self.mesh.element_sets[name]]
                nodes.append(self.node_of_dof[dofs.ravel()])
            if name in self.mesh.facet_sets:
                nodes.append(self.face_nodes(self.mesh.facet_sets[name]).ravel())
            if name in self.mesh.line_sets and len(self.mesh.line_sets[name]):
                nodes.append(self.edge_nodes(self.mesh.line_sets[name]))
        return np.unique(np.concatenate(nodes)).astype(np.int32)

    def face_nodes(self, faces: np.ndarray) -> np.ndarray:
        """(F, 2k) FE nodes of faces given by (F, k) cyclic corners: corners, then the midside
        node of edge (c0, c1), (c1, c2), ... (order 2); the corners as they are for order 1."""
        faces = np.asarray(faces, dtype=np.int64)
        if self.order == 1:
            return faces
        k = faces.shape[1]
        pairs = np.stack([faces, np.roll(faces, -1, axis=1)], axis=-1)      # (F, k, 2)
        return np.hstack([faces, self.edge_nodes(pairs.reshape(-1, 2)).reshape(-1, k)])

    def face_triangles(self, faces: np.ndarray) -> np.ndarray:
        """Linear triangles over all FE nodes of (F, 3 or 4) outward faces, same orientation.

        Order 1: a triangle as it is, a quad split along 0-2. Order 2: a 6-node triangle into
        its 4 sub-triangles; an 8-node quad into its 4 corner triangles and the midside quad
        split along a diagonal (6 triangles).
        """
        faces = np.asarray(faces, dtype=np.int64)
        fn = self.face_nodes(faces)
        if self.order == 1:
            local = [[0, 1, 2]] if faces.shape[1] == 3 else [[0, 1, 2], [0, 2, 3]]
        elif faces.shape[1] == 3:   # corners 0-2, midsides 3 (0-1), 4 (1-2), 5 (2-0)
            local = [[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]]
        else:                       # corners 0-3, midsides 4 (0-1), 5 (1-2), 6 (2-3), 7 (3-0)
            local = [[0, 4, 7], [4, 1, 5], [5, 2, 6], [6, 3, 7], [4, 5, 6], [4, 6, 7]]
        return np.ascontiguousarray(fn[:, local].reshape(-1, 3), dtype=np.int32)


def fe_space(mesh: FEMesh, order: int = 2) -> FESpace:
    """The vector FE space of ``mesh`` with elements of ``order`` (1 or 2), see the module.

    Raises
    ------
    ValueError
        If ``order`` is not 1 or 2.
    """
    if order not in (1, 2):
        raise ValueError(f"element_order must be 1 or 2 (got {order!r})")
    elem_cls, intorder, cell_type = ELEMENTS[mesh.kind][order]
    basis = skfem.Basis(mesh.mesh, skfem.ElementVector(elem_cls()), intorder=intorder)
    parts = [d for d in (basis.nodal_dofs, basis.edge_dofs, basis.facet_dofs, basis.interior_dofs)
             if d.size]
    nodal_dofs = np.hstack(parts).astype(np.int64)
    node_of_dof = np.empty(basis.N, dtype=np.int64)
    for c in range(3):
        node_of_dof[nodal_dofs[c]] = np.arange(nodal_dofs.shape[1])
    points = np.ascontiguousarray(basis.doflocs[:, nodal_dofs[0]].T, dtype=np.float64)
    return FESpace(mesh, order, cell_type, intorder, basis, nodal_dofs, points, node_of_dof)


def hrz_mass(basis: skfem.CellBasis, density: float) -> np.ndarray:
    """HRZ-lumped mass (kg) per DOF, (Ndofs,), every entry strictly positive.

    Per element and direction ``m_ii = M_ii m_e / sum_j M_jj`` (Hinton, Rock & Zienkiewicz
    1976), ``M_ii`` the diagonal of the consistent mass ``int rho phi_i . phi_i dV``, the sum
    over the element's DOFs of the same direction, ``m_e = rho V_e``.

    Raises
    ------
    ValueError
        If a mass is not strictly positive (a node without elements).
    """
    rho = float(density)
    dx = basis.dx                                                    # (Ne, nq)
    phi = local_values(basis)                                        # (nloc, 3, Ne, nq)
    diag = rho * np.einsum("icen,icen,en->ie", phi, phi, dx)        # (nloc, Ne)
    comp = np.argmax(np.abs(phi).sum(axis=(2, 3)), axis=1)          # direction of local DOF
    m_e = rho * dx.sum(axis=1)
    out = np.empty_like(diag)
    for c in range(3):
        sel = comp == c
        out[sel] = diag[sel] * (m_e / diag[sel].sum(axis=0))
    m = assemble_vector(basis, out)
    if not np.all(m > 0.0):
        raise ValueError(f"HRZ lumped mass has {int(np.sum(~(m > 0.0)))} non-positive entries "
                         f"(min {m.min():.3e} kg); the mesh has nodes without elements")
    return m
