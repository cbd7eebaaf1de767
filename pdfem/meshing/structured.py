"""Conforming hexahedral meshes of unions of axis-aligned boxes, built on a tensor grid.

A structure made of axis-aligned boxes (plating, flat bars, webs, flanges, a validation block)
is meshed without a mesh generator: the break points of all boxes along x, y and z, each
interval divided into a given number of cells (:func:`grid_axis`), form a tensor grid; the
cells whose centres lie in a box are the hexahedra (:func:`box_union_hexes`). Neighbouring
cells share their grid nodes, so the mesh is conforming by construction (no hanging nodes).
:func:`boundary_quads` finds the faces on the boundary, outward-oriented, and
:func:`add_discrete_mesh` hands nodes, hexahedra, quadrilateral and line groups to the open
gmsh session as discrete entities, ready for :func:`~pdfem.meshing.finish.finish_mesh`.

Lengths in m. Hexahedra are in gmsh's node order (corners 0-3 at the lower z, counter-clockwise
seen from +z, then 4-7 above them), so their Jacobian is positive.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from pdfem.meshing.elements import HEX_FACES

__all__ = ["FACE_AXIS", "add_discrete_mesh", "boundary_quads", "box_union_hexes", "grid_axis", "merge_breaks"]

#: for each row of :data:`~pdfem.meshing.elements.HEX_FACES`: (axis, +1 / -1) of its outward normal
FACE_AXIS = ((2, -1), (2, 1), (1, -1), (0, 1), (1, 1), (0, -1))

# gmsh corner order on the (i, j, k) cell offsets
_CORNER_OFFSETS = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                            [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]])


def merge_breaks(points: Sequence[float], tol: float) -> np.ndarray:
    """Sorted break points with those closer than ``tol`` (m) merged (the first one kept)."""
    p = np.sort(np.asarray(points, dtype=float))
    keep = np.concatenate([[True], np.diff(p) > tol])
    return p[keep]


def grid_axis(breaks: np.ndarray, divisions: Sequence[int]) -> np.ndarray:
    """Grid coordinates along one axis: interval k of ``breaks`` split into ``divisions[k]``
    equal cells (>= 1)."""
    parts = [np.linspace(a, b, int(n) + 1)[:-1] for a, b, n in zip(breaks[:-1], breaks[1:], divisions)]
    return np.concatenate(parts + [breaks[-1:]])


def box_union_hexes(axes: tuple[np.ndarray, np.ndarray, np.ndarray],
                    boxes: Sequence[Sequence[float]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The hexahedra of the tensor grid ``axes`` whose centres lie in one of ``boxes``.

    Parameters
    ----------
    axes
        Grid coordinates along x, y, z (m), each increasing; every box face lies on a grid plane.
    boxes
        ``(xmin, xmax, ymin, ymax, zmin, zmax)`` of each box, m.

    Returns
    -------
    nodes
        (N, 3) coordinates of the nodes the hexahedra use, m.
    hexes
        (M, 8) rows into ``nodes``, gmsh order.
    cells
        (M, 3) grid indices (i, j, k) of each hexahedron's lowest corner.
    """
    centres = [0.5 * (a[1:] + a[:-1]) for a in axes]
    inside = np.zeros([len(c) for c in centres], dtype=bool)
    for b in boxes:
        masks = [(c > b[2 * d]) & (c < b[2 * d + 1]) for d, c in enumerate(centres)]
        inside |= masks[0][:, None, None] & masks[1][None, :, None] & masks[2][None, None, :]
    cells = np.argwhere(inside)
    shape = tuple(len(a) for a in axes)
    corner = (cells[:, None, :] + _CORNER_OFFSETS[None]).reshape(-1, 3)
    flat = np.ravel_multi_index(corner.T, shape)
    used, hexes = np.unique(flat, return_inverse=True)
    ijk = np.array(np.unravel_index(used, shape)).T
    nodes = np.column_stack([axes[d][ijk[:, d]] for d in range(3)])
    return nodes, hexes.reshape(-1, 8).astype(np.int64), cells


def boundary_quads(hexes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Faces of the hexahedra that belong to one hexahedron only, oriented outward.

    Returns
    -------
    quads
        (K, 4) corner rows, right-hand normal out of the mesh.
    side
        (K,) index of each face in :data:`~pdfem.meshing.elements.HEX_FACES` (see
        :data:`FACE_AXIS` for its normal's axis and sign).
    """
    faces = hexes[:, HEX_FACES].reshape(-1, 4)
    side = np.tile(np.arange(6), len(hexes))
    _, inv, counts = np.unique(np.sort(faces, axis=1), axis=0, return_inverse=True, return_counts=True)
    once = counts[inv.ravel()] == 1
    return faces[once], side[once]


def add_discrete_mesh(gmsh: Any, nodes: np.ndarray, hexes: np.ndarray, volume: str,
                      surfaces: dict[str, list[np.ndarray]],
                      lines: dict[str, list[np.ndarray]] | None = None) -> None:
    """Put a hexahedral mesh into the open gmsh session as discrete entities with named groups.

    Parameters
    ----------
    gmsh
        The gmsh module of an open :func:`~pdfem.meshing.session.gmsh_session`.
    nodes
        (N, 3) coordinates, m.
    hexes
        (M, 8) rows into ``nodes``, gmsh order.
    volume
        Name of the 3-D physical group of all hexahedra.
    surfaces
        Group name -> list of (K, 4) quadrilateral arrays (rows into ``nodes``); each array
        becomes one discrete surface, so an array listed under several names is one entity in
        several groups (pass the same array object).
    lines
        Group name -> list of (K, 2) line-segment arrays, likewise (1-D groups, e.g. support lines).
    """
    vol = gmsh.model.addDiscreteEntity(3)
    gmsh.model.mesh.addNodes(3, vol, np.arange(1, len(nodes) + 1), nodes.ravel())
    gmsh.model.mesh.addElementsByType(vol, 5, [], (hexes + 1).ravel())
    gmsh.model.addPhysicalGroup(3, [vol], name=volume)
    for dim, groups, etype in ((2, surfaces, 3), (1, lines or {}, 1)):
        entity: dict[int, int] = {}
        for name, arrays in groups.items():
            tags = []
            for arr in arrays:
                if len(arr) == 0:
                    continue
                if id(arr) not in entity:
                    tag = gmsh.model.addDiscreteEntity(dim)
                    gmsh.model.mesh.addElementsByType(tag, etype, [], (np.asarray(arr) + 1).ravel())
                    entity[id(arr)] = tag
                tags.append(entity[id(arr)])
            if tags:
                gmsh.model.addPhysicalGroup(dim, tags, name=name)
