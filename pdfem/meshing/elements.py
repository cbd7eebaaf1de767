"""The gmsh element types that model scripts may write, and their corner topology.

:func:`~pdfem.meshing.finish.finish_mesh` accepts volume meshes of one of
:data:`VOLUME_TYPES` (first- or second-order tetrahedra and hexahedra) with surface groups of
the matching face type (:data:`FACE_TYPES`), and surface meshes of :data:`SURFACE_TYPES`. In
every one of these gmsh types the corner nodes come first, in the order of the first-order
element, so the corner connectivity of a quadratic element is its first few columns and the
quality checks of :mod:`pdfem.meshing.quality` work on the corners (for a quadratic element:
the straight-sided element through its corners; gmsh's SICN also sees the curved shape).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["ElementType", "GMSH_TYPES", "VOLUME_TYPES", "SURFACE_TYPES", "FACE_TYPES", "HEX_FACES",
           "TET_FACES", "element_type", "meshio_name"]


class ElementType(NamedTuple):
    """One gmsh element type."""

    gmsh: int          #: gmsh element type number
    name: str          #: meshio cell type name
    dim: int           #: topological dimension
    nodes: int         #: nodes per element
    corners: int       #: corner (vertex) nodes, listed first
    order: int         #: polynomial order


_ALL = [
    ElementType(15, "vertex", 0, 1, 1, 1),
    ElementType(1, "line", 1, 2, 2, 1),
    ElementType(8, "line3", 1, 3, 2, 2),
    ElementType(2, "triangle", 2, 3, 3, 1),
    ElementType(9, "triangle6", 2, 6, 3, 2),
    ElementType(3, "quad", 2, 4, 4, 1),
    ElementType(16, "quad8", 2, 8, 4, 2),
    ElementType(10, "quad9", 2, 9, 4, 2),
    ElementType(4, "tetra", 3, 4, 4, 1),
    ElementType(11, "tetra10", 3, 10, 4, 2),
    ElementType(5, "hexahedron", 3, 8, 8, 1),
    ElementType(17, "hexahedron20", 3, 20, 8, 2),
    ElementType(12, "hexahedron27", 3, 27, 8, 2),
    ElementType(6, "wedge", 3, 6, 6, 1),
    ElementType(7, "pyramid", 3, 5, 5, 1),
]

#: gmsh type number -> :class:`ElementType`
GMSH_TYPES: dict[int, ElementType] = {e.gmsh: e for e in _ALL}

#: volume element types a model may write: tetra, tetra10, hexahedron, hexahedron20, hexahedron27
VOLUME_TYPES = (4, 11, 5, 17, 12)
#: surface element types of a surface-only model (closed rigid surfaces)
SURFACE_TYPES = (2, 9, 3, 16, 10)
#: volume type -> the face types its surface groups may have (the same order, or first-order faces)
FACE_TYPES = {4: (2,), 11: (9,), 5: (3,), 17: (16,), 12: (10,)}

#: corner nodes of the four faces of a gmsh tetrahedron
TET_FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
#: corner nodes of the six faces of a gmsh hexahedron (outward normals by the right-hand rule)
HEX_FACES = np.array([[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [0, 4, 7, 3]])


def element_type(gmsh_type: int) -> ElementType:
    """The :class:`ElementType` of a gmsh type number (KeyError for types not listed here)."""
    return GMSH_TYPES[int(gmsh_type)]


def meshio_name(gmsh_type: int) -> str:
    """meshio's name of a gmsh element type, or ``"gmsh type N"`` for one not listed here."""
    e = GMSH_TYPES.get(int(gmsh_type))
    return e.name if e else f"gmsh type {int(gmsh_type)}"
