"""Quality measures of first-order tetrahedra and triangles, and the check that refuses bad cells.

A mesh for the explicit structure solver must have no inverted or (near) zero-volume elements,
and its smallest element limits the stable time step. This module holds the measures the model
scripts (through :func:`pdfem.meshing.finish.finish_mesh`) report and check:

* :func:`tet_volumes`, :func:`triangle_areas` -- signed volumes (m^3), areas (m^2);
* :func:`tet_min_dihedral`, :func:`triangle_min_angle` -- smallest angles (deg);
* :func:`tet_inradii`, :func:`triangle_inradii` -- inscribed radii (m);
* :func:`longest_edges` -- longest edge of each cell (m);
* :func:`check_cells` -- all of them at once, raising :class:`MeshQualityError` for inverted or
  degenerate cells.

All functions take ``points`` (N, 3) in m and ``cells`` (M, 4) tetrahedra or (M, 3) triangles
as integer rows into ``points``, and return one value per cell.
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
    "longest_edges",
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
    p = points[tris]
    worst = np.full(len(tris), np.pi)
    for k in range(3):
        u = p[:, (k + 1) % 3] - p[:, k]
        v = p[:, (k + 2) % 3] - p[:, k]
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

    size: np.ndarray       #: volume (m^3) of each tetrahedron, or area (m^2) of each triangle; all > 0
    min_angle: np.ndarray  #: smallest dihedral (tetrahedra) or interior (triangles) angle, deg
    inradius: np.ndarray   #: inscribed sphere (circle) radius, m


def check_cells(points: np.ndarray, cells: np.ndarray, dim: int) -> CellQuality:
    """Measure the cells of a tetrahedral (``dim == 3``) or triangle (``dim == 2``) mesh and
    refuse inverted or degenerate ones.

    Parameters
    ----------
    points
        (N, 3) node coordinates, m.
    cells
        (M, 4) tetrahedra in gmsh's right-handed node order, or (M, 3) triangles.
    dim
        3 or 2.

    Returns
    -------
    CellQuality
        Sizes, smallest angles and inscribed radii of the cells.

    Raises
    ------
    MeshQualityError
        No cells; inverted or zero-volume tetrahedra (signed volume <= 0); or (near) zero-volume
        cells: size / longest edge^dim below :data:`DEGENERATE`.
    """
    if len(cells) == 0:
        raise MeshQualityError("the mesh has no elements")
    longest = longest_edges(points, cells)
    if dim == 3:
        size = tet_volumes(points, cells)
        bad = size <= 0
        if bad.any():
            raise MeshQualityError(f"{int(bad.sum())} inverted or zero-volume tetrahedra "
                                   f"(smallest signed volume {size.min():.3g} m^3)")
        angle = tet_min_dihedral(points, cells)
        inradius = tet_inradii(points, cells)
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
