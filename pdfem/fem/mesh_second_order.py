"""Second-order gmsh cells: their corner nodes, and isoparametric 10-node tetrahedra.

meshio lists the corners of a second-order cell first (as gmsh does) and its midside nodes in
VTK order. :func:`corners` keeps the corners of any cell; :func:`isoparametric_tet` builds a
:class:`skfem.MeshTet2` keeping the midside node positions (m) of a tetra10 mesh (curved
elements). :func:`edge_lookup` finds mesh edges by their corner pairs.
"""

from __future__ import annotations

import numpy as np
import skfem

#: meshio cell type -> (kind, number of corner nodes first in the cell).
CORNERS = {"tetra": ("tet", 4), "tetra10": ("tet", 4), "hexahedron": ("hex", 8),
           "hexahedron20": ("hex", 8), "hexahedron27": ("hex", 8),
           "triangle": ("tri", 3), "triangle6": ("tri", 3), "quad": ("quad", 4),
           "quad8": ("quad", 4), "quad9": ("quad", 4), "line": ("line", 2), "line3": ("line", 2)}


def edge_lookup(edges: np.ndarray, n_vertices: int, pairs: np.ndarray) -> np.ndarray:
    """Index in ``edges`` (2, Ned) of each corner pair of ``pairs`` (..., 2); -1 if absent."""
    e = np.sort(edges, axis=0).astype(np.int64)
    keys = e[0] * n_vertices + e[1]
    order = np.argsort(keys)
    p = np.sort(np.asarray(pairs, dtype=np.int64), axis=-1)
    q = p[..., 0] * n_vertices + p[..., 1]
    pos = np.clip(np.searchsorted(keys[order], q), 0, len(keys) - 1)
    return np.where(keys[order][pos] == q, order[pos], -1)


def isoparametric_tet(mesh: skfem.MeshTet1, points: np.ndarray, renum: np.ndarray,
                       full: np.ndarray) -> skfem.MeshTet2:
    """A :class:`skfem.MeshTet2` with the midside node positions (m) of the file's tetra10
    cells ``full`` (meshio / VTK order: midsides of (0,1), (1,2), (0,2), (0,3), (1,3), (2,3))."""
    pairs = np.array([(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)])
    corner = renum[full[:, :4]]
    e = edge_lookup(mesh.edges, mesh.nvertices, corner[:, pairs])          # (n, 6)
    mid = np.empty((3, mesh.edges.shape[1]))
    mid[:, e.ravel()] = points[full[:, 4:]].reshape(-1, 3).T
    return skfem.MeshTet2(np.hstack([mesh.p, mid]), mesh.t)


def corners(cell_type: str, cells: np.ndarray) -> tuple[str, np.ndarray]:
    """``(kind, corner connectivity)`` of a block of cells (other types: as they are)."""
    if cell_type not in CORNERS:
        return cell_type, cells
    kind, nc = CORNERS[cell_type]
    return kind, cells[:, :nc]
