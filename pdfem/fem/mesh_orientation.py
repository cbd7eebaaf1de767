"""Orientation checks of first-order volume elements read from a mesh file (SI: metres).

Tetrahedra by their signed volume, hexahedra by their eight corner Jacobians (gmsh / VTK corner
order). :func:`check_orientation` renumbers simply inverted elements to positive orientation and
refuses degenerate or partly inverted (tangled) ones with a message naming the element.
"""

from __future__ import annotations

import numpy as np

# Relative size below which an element's volume counts as zero: |corner Jacobian| / l_max^3.
_DEGENERATE = 1e-10


def _tet_orientation(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Relative signed volume 6 V / l_max^3 of each tetrahedron (t in gmsh order, (n, 4))."""
    x = p[t]
    e = x[:, 1:] - x[:, :1]
    det = np.einsum("ij,ij->i", e[:, 0], np.cross(e[:, 1], e[:, 2]))
    edges = np.concatenate([e, x[:, [2, 3, 3]] - x[:, [1, 1, 2]]], axis=1)
    lmax = np.sqrt(np.max(np.einsum("ijk,ijk->ij", edges, edges), axis=1))
    return det / lmax**3


def _hex_corner_jacobians(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Relative corner Jacobians (n, 8) of trilinear hexahedra in gmsh/VTK node order.

    Bottom face 0-1-2-3 (counter-clockwise seen from the top), top face 4-5-6-7 above it. At a
    corner the Jacobian columns are the two face edges leaving it (next, previous around its face)
    and the edge from the bottom node to the top node; all are positive for a valid element.
    """
    x = p[t]
    nxt = np.array([1, 2, 3, 0])
    prv = np.array([3, 0, 1, 2])
    up = x[:, 4:] - x[:, :4]                                        # (n, 4, 3)
    jb = np.einsum("nij,nij->ni", x[:, nxt] - x[:, :4],
                   np.cross(x[:, prv] - x[:, :4], up))
    jt = np.einsum("nij,nij->ni", x[:, nxt + 4] - x[:, 4:],
                   np.cross(x[:, prv + 4] - x[:, 4:], up))
    edges = np.concatenate([x[:, nxt] - x[:, :4], x[:, nxt + 4] - x[:, 4:], up], axis=1)
    lmax = np.sqrt(np.max(np.einsum("nij,nij->ni", edges, edges), axis=1))
    return np.hstack([jb, jt]) / lmax[:, None] ** 3


def check_orientation(path: str, p: np.ndarray, t: np.ndarray, kind: str) -> np.ndarray:
    """Return ``t`` (gmsh order) with simply inverted elements renumbered; refuse bad ones."""
    t = t.copy()
    if kind == "tet":
        rel = _tet_orientation(p, t)[:, None]
    else:
        rel = _hex_corner_jacobians(p, t)
    bad = np.abs(rel).min(axis=1) <= _DEGENERATE
    mixed = (rel.max(axis=1) > 0) & (rel.min(axis=1) < 0)
    for mask, what in ((bad, "degenerate (zero volume)"), (mixed, "partly inverted (tangled)")):
        if mask.any():
            e = int(np.flatnonzero(mask)[0])
            raise ValueError(
                f"{path}: {int(mask.sum())} {kind} element(s) are {what}, e.g. element {e} with "
                f"nodes at {np.round(p[t[e]], 9).tolist()}; remesh the model")
    flip = rel.max(axis=1) < 0
    if flip.any():
        if kind == "tet":
            t[flip] = t[flip][:, [0, 2, 1, 3]]
        else:
            t[flip] = t[flip][:, [4, 5, 6, 7, 0, 1, 2, 3]]
    return t
