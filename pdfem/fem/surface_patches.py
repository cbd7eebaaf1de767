"""Load patches of a triangulated surface mesh: which contact triangles lie on each other group.

A rigid body or a ship is read from the contact group of a surface mesh
(:func:`pdfem.motion.rigid.read_surface`). The file's other surface groups (a hull's ``bow``,
``shoulder``, ``midship``, ...) name parts of that surface; each becomes a load patch whose
force history the run writes (:mod:`pdfem.coupling.facet_loads`). A contact triangle belongs
to a group when the group has a triangle (or half of a quadrilateral) on the same three points,
matched by coordinates (m) since the contact surface is renumbered on reading.
"""

from __future__ import annotations

import os

import numpy as np

from pdfem.fem.mesh import read_msh_groups
from pdfem.fem.surface import split_quads


def _keys(points: np.ndarray, triangles: np.ndarray) -> list[tuple]:
    """One key per triangle: its three points' coordinates (m), sorted."""
    corners = points[np.asarray(triangles, dtype=np.int64)].tolist()     # (T, 3, 3)
    return [tuple(sorted(map(tuple, c))) for c in corners]


def surface_patches(path: str | os.PathLike, contact_group: str, points: np.ndarray,
                    triangles: np.ndarray) -> dict[str, np.ndarray]:
    """``{group: (T,) bool}`` for every other surface group of ``path`` sharing triangles with
    the contact surface (``points`` (N, 3) m, ``triangles`` (T, 3) as read); a volume mesh or a
    file without such groups gives ``{}``."""
    raw = read_msh_groups(path)
    if raw.volume_cells or len(triangles) == 0:
        return {}
    contact = _keys(points, triangles)
    own = set(contact)
    out = {}
    for name, (dim, blocks) in sorted(raw.groups.items()):
        if dim != 2 or name == contact_group:
            continue
        cells = [split_quads(c) for ct, c in blocks if ct in ("triangle", "quad")]
        if not cells:
            continue
        group = set(_keys(raw.points, np.vstack(cells)))
        if not group & own:
            continue
        out[name] = np.fromiter((key in group for key in contact), bool, len(contact))
    return out
