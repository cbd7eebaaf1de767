"""Quality measures of tetrahedra, hexahedra, triangles and quadrilaterals (by their corner
nodes), and the check that refuses bad cells.

A mesh for the explicit structure solver must have no inverted or (near) zero-volume elements,
and its smallest element limits the stable time step. This module holds the measures the model
scripts (through :func:`pdfem.meshing.finish.finish_mesh`) report and check:

* :func:`tet_volumes`, :func:`triangle_areas` -- signed volumes (m^3), areas (m^2);
* :func:`tet_min_dihedral`, :func:`triangle_min_angle` -- smallest angles (deg);
* :func:`tet_inradii`, :func:`triangle_inradii` -- inscribed radii (m);
* :func:`hex_corner_jacobians`, :func:`hex_volumes`, :func:`hex_min_angle`, :func:`hex_inradii`
  -- the same for (trilinear) hexahedra: corner Jacobians, volumes (exact, 2x2x2 Gauss), smallest
  angle between two edges at a corner (deg), half the smallest height;
* :func:`quad_areas`, :func:`quad_min_angle` -- areas (m^2, of planar quadrilaterals) and
  smallest corner angles (deg);
* :func:`longest_edges` -- longest edge of each cell (m);
* :func:`check_cells` -- all of them at once, raising :class:`MeshQualityError` for inverted or
  degenerate cells.

All functions take ``points`` (N, 3) in m and ``cells`` (M, 4) tetrahedra, (M, 8) hexahedra,
(M, 3) triangles or (M, 4) quadrilaterals as integer rows into ``points`` in gmsh's corner
order, and return one value per cell. Quadratic elements are measured by their corners (the
first columns of their gmsh connectivity).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from pdfem.errors import InputError

__all__ = [
    "DEGENERATE",
    "MeshQualityError",
    "CellQuality",
    "check_cells",
    "hex_corner_jacobians",
    "hex_inradii",
    "hex_min_angle",
    "hex_volumes",
    "longest_edges",
    "quad_areas",
    "quad_min_angle",
    "tet_volumes",
    "tet_min_dihedral",
    "tet_inradii",
    "triangle_areas",
    "triangle_min_angle",
    "triangle_inradii",
]

#: Elements with a normalised size (volume / longest edge^3, area / longest edge^2) below this
#: are treated as zero-volume (degenerate). A regular tetrahedron has 0.118, a regular triangle
#: 0.433; gmsh's worst acceptable slivers are many orders of magnitude above 1e-8.
DEGENERATE = 1e-8


class MeshQualityError(InputError, ValueError):
    """A generated mesh that must not be used: inverted or zero-volume elements, or a surface
    that should be closed and consistently oriented but is not.

    Parameters
    ----------
    message
        What is wrong with the mesh, as a sentence.
    file
        The mesh file concerned, if known.
    """

    def __init__(self, message: str, file: str | None = None):
        super().__init__(file, None, message)


def tet_volumes(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Signed volumes (m^3) of tetrahedra, positive for gmsh's (right-handed) node order."""
    a, b, c, d = (points[tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0


def tet_min_dihedral(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Smallest dihedral angle (deg) of each tetrahedron."""
    p = points[tets]                                     # (M,4,3)
    # outward normal of the face opposite vertex k
    normals = []
    for k in range(4):
        i, j, l = [m for m in range(4) if m != k]
        n = np.cross(p[:, j] - p[:, i], p[:, l] - p[:, i])
        s = np.sign(np.einsum("ij,ij->i", n, p[:, i] - p[:, k]))[:, None]
        n = n * s
        normals.append(n / np.linalg.norm(n, axis=1)[:, None])
    worst = np.full(len(tets), np.pi)
    for k in range(4):
        for m in range(k + 1, 4):
            cosang = np.clip(np.einsum("ij,ij->i", normals[k], normals[m]), -1.0, 1.0)
            worst = np.minimum(worst, np.pi - np.arccos(cosang))
    return np.degrees(worst)


def triangle_areas(points: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Areas (m^2) of triangles."""
    a, b, c = (points[tris[:, k]] for k in range(3))
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def triangle_min_angle(points: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Smallest interior angle (deg) of each triangle."""
    return polygon_min_angle(points, tris)


def polygon_min_angle(points: np.ndarray, polys: np.ndarray) -> np.ndarray:
    """Smallest interior corner angle (deg) of each polygon (rows of corner nodes in order)."""
    p = points[polys]
    n = polys.shape[1]
    worst = np.full(len(polys), np.pi)
    for k in range(n):
        u = p[:, (k + 1) % n] - p[:, k]
        v = p[:, (k - 1) % n] - p[:, k]
        cosang = np.einsum("ij,ij->i", u, v) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
        worst = np.minimum(worst, np.arccos(np.clip(cosang, -1.0, 1.0)))
    return np.degrees(worst)


def tet_inradii(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Radii (m) of the inscribed spheres of tetrahedra: 3 |V| / (sum of the face areas)."""
    faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]], tets[:, [0, 1, 2]]])
    area = triangle_areas(points, faces).reshape(4, -1).sum(axis=0)
    return 3.0 * np.abs(tet_volumes(points, tets)) / area


def triangle_inradii(points: np.ndarray, tris: np.ndarray) -> np.ndarray:
    """Radii (m) of the inscribed circles of triangles: 2 A / perimeter."""
    p = points[tris]
    perimeter = sum(np.linalg.norm(p[:, (k + 1) % 3] - p[:, k], axis=1) for k in range(3))
    return 2.0 * triangle_areas(points, tris) / perimeter


# the three edge neighbours of each hexahedron corner, in right-handed order (gmsh numbering)
_HEX_CORNER_EDGES = np.array([[1, 3, 4], [2, 0, 5], [3, 1, 6], [0, 2, 7],
                              [7, 5, 0], [4, 6, 1], [5, 7, 2], [6, 4, 3]])
_HEX_FACES = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [2, 3, 7, 6], [1, 2, 6, 5], [0, 4, 7, 3]])


def hex_corner_jacobians(points: np.ndarray, hexes: np.ndarray) -> np.ndarray:
    """(M, 8) triple products of the three edges at each corner (m^3), all positive for a
    valid hexahedron in gmsh's (right-handed) node order; 8 x the volume for a parallelepiped."""
    p = points[hexes]                                   # (M,8,3)
    c = _HEX_CORNER_EDGES
    e = p[:, c] - p[:, :, None, :]                      # (M,8,3 edges,3)
    return np.einsum("mkj,mkj->mk", e[:, :, 0], np.cross(e[:, :, 1], e[:, :, 2]))


def hex_volumes(points: np.ndarray, hexes: np.ndarray) -> np.ndarray:
    """Signed volumes (m^3) of trilinear hexahedra: det J integrated by 2x2x2 Gauss points
    (exact: det J is of degree 2 in each reference coordinate)."""
    p = points[hexes]
    ref = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                    [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)
    g = 1.0 / np.sqrt(3.0)
    vol = np.zeros(len(hexes))
    for q in np.array(np.meshgrid([-g, g], [-g, g], [-g, g])).reshape(3, -1).T:
        f = 1.0 + ref * q                                # (8,3) factors of the shape functions
        dn = np.stack([ref[:, 0] * f[:, 1] * f[:, 2], ref[:, 1] * f[:, 0] * f[:, 2],
                       ref[:, 2] * f[:, 0] * f[:, 1]], axis=1) / 8.0    # (8,3) dN/dxi
        jac = np.einsum("mki,kj->mij", p, dn)            # (M,3 x,3 xi)
        vol += np.linalg.det(jac)
    return vol


def hex_min_angle(points: np.ndarray, hexes: np.ndarray) -> np.ndarray:
    """Smallest angle (deg) between two edges meeting at a corner of each hexahedron (90 for a box)."""
    p = points[hexes]
    e = p[:, _HEX_CORNER_EDGES] - p[:, :, None, :]
    e = e / np.linalg.norm(e, axis=3, keepdims=True)
    cos = np.stack([np.einsum("mkj,mkj->mk", e[:, :, a], e[:, :, b]) for a, b in ((0, 1), (1, 2), (0, 2))])
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)).min(axis=(0, 2)))


def hex_inradii(points: np.ndarray, hexes: np.ndarray) -> np.ndarray:
    """Half the smallest height (m) of each hexahedron: 0.5 min over the three pairs of opposite
    faces of |V| / (mean area of the pair); half the shortest edge for a box."""
    vol = np.abs(hex_volumes(points, hexes))
    area = quad_areas(points, hexes[:, _HEX_FACES].reshape(-1, 4)).reshape(len(hexes), 6)
    pairs = 0.5 * (area[:, 0::2] + area[:, 1::2])
    return 0.5 * vol / pairs.max(axis=1)


def quad_areas(points: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """Areas (m^2) of quadrilaterals, half the cross product of the diagonals (exact if planar)."""
    a, b, c, d = (points[quads[:, k]] for k in range(4))
    return 0.5 * np.linalg.norm(np.cross(c - a, d - b), axis=1)


def quad_min_angle(points: np.ndarray, quads: np.ndarray) -> np.ndarray:
    """Smallest interior corner angle (deg) of each quadrilateral."""
    return polygon_min_angle(points, quads)


def longest_edges(points: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Length (m) of the longest edge of each cell (any number of nodes per cell)."""
    n = cells.shape[1]
    best = np.zeros(len(cells))
    for i in range(n):
        for j in range(i + 1, n):
            best = np.maximum(best, np.linalg.norm(points[cells[:, j]] - points[cells[:, i]], axis=1))
    return best


class CellQuality(NamedTuple):
    """Per-cell measures of a checked mesh (see :func:`check_cells`)."""

    size: np.ndarray       #: volume (m^3) of each volume cell, or area (m^2) of each surface cell; all > 0
    min_angle: np.ndarray  #: smallest dihedral (tetrahedra), edge (hexahedra) or interior (triangles, quads) angle, deg
    inradius: np.ndarray   #: inscribed sphere (circle) radius, m


def check_cells(points: np.ndarray, cells: np.ndarray, dim: int) -> CellQuality:
    """Measure the cells of a tetrahedral or hexahedral (``dim == 3``) or triangle or
    quadrilateral (``dim == 2``) mesh by their corners and refuse inverted or degenerate ones.

    Parameters
    ----------
    points
        (N, 3) node coordinates, m.
    cells
        Corner connectivity in gmsh's right-handed node order: (M, 4) tetrahedra or (M, 8)
        hexahedra for ``dim == 3``, (M, 3) triangles or (M, 4) quadrilaterals for ``dim == 2``.
    dim
        3 or 2.

    Returns
    -------
    CellQuality
        Sizes, smallest angles and inscribed radii of the cells.

    Raises
    ------
    MeshQualityError
        No cells; inverted or zero-volume tetrahedra (signed volume <= 0) or hexahedra (a corner
        Jacobian <= 0); or (near) zero-volume cells: size / longest edge^dim below
        :data:`DEGENERATE`.
    """
    if len(cells) == 0:
        raise MeshQualityError("the mesh has no elements")
    longest = longest_edges(points, cells)
    if dim == 3 and cells.shape[1] == 8:
        size = hex_volumes(points, cells)
        corner = hex_corner_jacobians(points, cells).min(axis=1)
        bad = corner <= 0
        if bad.any():
            raise MeshQualityError(f"{int(bad.sum())} inverted, partly inverted or zero-volume hexahedra "
                                   f"(smallest corner Jacobian {corner.min():.3g} m^3)")
        angle = hex_min_angle(points, cells)
        inradius = hex_inradii(points, cells)
    elif dim == 3:
        size = tet_volumes(points, cells)
        bad = size <= 0
        if bad.any():
            raise MeshQualityError(f"{int(bad.sum())} inverted or zero-volume tetrahedra "
                                   f"(smallest signed volume {size.min():.3g} m^3)")
        angle = tet_min_dihedral(points, cells)
        inradius = tet_inradii(points, cells)
    elif cells.shape[1] == 4:
        size = quad_areas(points, cells)
        angle = quad_min_angle(points, cells)
        perimeter = sum(np.linalg.norm(points[cells[:, (k + 1) % 4]] - points[cells[:, k]], axis=1)
                        for k in range(4))
        inradius = 2.0 * size / perimeter
    else:
        size = triangle_areas(points, cells)
        angle = triangle_min_angle(points, cells)
        inradius = triangle_inradii(points, cells)
    degenerate = size / longest**dim < DEGENERATE
    if degenerate.any():
        raise MeshQualityError(f"{int(degenerate.sum())} (near) zero-volume elements: the smallest has "
                               f"{'volume' if dim == 3 else 'area'} {size.min():.3g} with longest edge "
                               f"{longest[np.argmin(size)]:.3g} m")
    return CellQuality(size, angle, inradius)
