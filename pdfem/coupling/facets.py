"""Triangulated contact surfaces for the narrow phase: closest points and pseudo-normals.

Which side of a surface a point is on is decided by the sign of ``(p - c) . n`` where ``c`` is
the closest point of the surface and ``n`` the angle-weighted pseudo-normal of the feature
(face, edge or vertex) that ``c`` lies on (Baerentzen & Aanaes, "Signed distance computation
using the angle weighted pseudonormal", IEEE TVCG 11, 2005). Face normals alone give the wrong
side for points closest to an edge or a vertex of a convex corner; the pseudo-normals do not,
for any closed, consistently oriented surface.

Features are numbered per triangle (a, b, c): 0 the face, 1..3 the vertices a, b, c, 4..6 the
edges ab, bc, ca. :class:`FacetTopology` is the fixed part (edges, which features lie on the
boundary of an open surface); :func:`pseudo_normals` the part that changes as the surface
moves, and :func:`pseudo_normals_of` the same for a part of the surface (the facets near the
ice and those around them, :mod:`pdfem.coupling.near_facets`: the contact takes them every
coupling step). All lengths in m.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numba
import numpy as np

FACE = 0
"""Feature code of a triangle's interior."""


@dataclass(frozen=True)
class FacetTopology:
    """Edges of a triangulated surface and its open boundary.

    Attributes
    ----------
    triangles
        (T, 3) int32 node indices, outward oriented.
    tri_edges
        (T, 3) int32 edge index of edges ab, bc, ca of each triangle.
    n_edges
        Number of distinct edges.
    boundary_edge
        (E,) bool, edges with one triangle (the rim of an open surface).
    boundary_node
        (Ns,) bool, nodes on such an edge.
    """

    triangles: np.ndarray
    tri_edges: np.ndarray
    n_edges: int
    boundary_edge: np.ndarray
    boundary_node: np.ndarray

    @classmethod
    def from_triangles(cls, triangles: np.ndarray, n_nodes: int) -> "FacetTopology":
        """Find the edges of ``triangles`` ((T, 3) indices into ``n_nodes`` nodes)."""
        tri = np.ascontiguousarray(triangles, dtype=np.int32)
        if tri.ndim != 2 or tri.shape[1] != 3 or len(tri) == 0:
            raise ValueError(f"a contact surface needs (T, 3) triangles with T > 0, got {tri.shape}")
        e = np.stack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]], axis=1).reshape(-1, 2)
        key = np.sort(e, axis=1)
        uniq, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        boundary_edge = count == 1
        boundary_node = np.zeros(n_nodes, dtype=bool)
        boundary_node[uniq[boundary_edge].ravel()] = True
        return cls(tri, inv.reshape(-1, 3).astype(np.int32), len(uniq), boundary_edge,
                   boundary_node)


def pseudo_normals(points: np.ndarray, topo: FacetTopology):
    """Unit normals of faces, edges and vertices in the current configuration.

    Parameters
    ----------
    points
        (Ns, 3) current node positions (m).
    topo
        The surface's :class:`FacetTopology`.

    Returns
    -------
    face, edge, vertex : numpy.ndarray
        (T, 3) face normals (right-hand rule = outward), (E, 3) edge pseudo-normals (the mean
        of the two faces' normals; the face's own on a boundary edge) and (Ns, 3) vertex
        pseudo-normals (incident face normals weighted by the face's angle at the vertex).

    Raises
    ------
    ValueError
        If a facet has zero area.
    """
    pts = np.ascontiguousarray(points, dtype=np.float64)
    normals = (np.empty((len(topo.triangles), 3)), np.empty((topo.n_edges, 3)),
               np.empty((len(pts), 3)))
    whole = FacetPart(np.arange(len(topo.triangles), dtype=np.int32),
                      np.arange(topo.n_edges, dtype=np.int32), np.arange(len(pts), dtype=np.int32))
    pseudo_normals_of(pts, topo, whole, normals)
    return normals


class FacetPart(NamedTuple):
    """A part of a surface whose pseudo-normals are computed: its triangles (ascending), and
    the edges and nodes of those triangles (int32 index arrays)."""

    triangles: np.ndarray
    edges: np.ndarray
    nodes: np.ndarray


def pseudo_normals_of(points: np.ndarray, topo: FacetTopology, part: FacetPart,
                      normals: tuple[np.ndarray, np.ndarray, np.ndarray]) -> None:
    """The pseudo-normals of a part of the surface, written into the rows of ``normals``
    (``(face, edge, vertex)``, the whole surface's arrays, as :func:`pseudo_normals` returns)
    of its triangles, edges and nodes; the other rows are left alone.

    An edge's or a vertex's normal is the whole surface's, bit for bit, when ``part`` holds
    every triangle around it: the sums run over the part's triangles in ascending order, the
    order of the whole surface's pass.

    Parameters
    ----------
    points
        (Ns, 3) current node positions (m), float64, C-contiguous.
    topo
        The surface's :class:`FacetTopology`.
    part
        The triangles, edges and nodes to compute (:class:`FacetPart`).
    normals
        ``(face, edge, vertex)``: (T, 3), (E, 3), (Ns, 3) float64 arrays, written in place.

    Raises
    ------
    ValueError
        If a facet of the part has zero area.
    """
    face, edge, vertex = normals
    degenerate = _pseudo_normals(points, topo.triangles, topo.tri_edges, part, face, edge,
                                 vertex)
    if degenerate:
        raise ValueError(f"{degenerate} contact facets have zero area")


@numba.njit(cache=True)
def _pseudo_normals(pts, tri, tri_edges, part, face, edge, vertex):
    """Fill the rows of ``face``, ``edge`` and ``vertex`` of ``part``'s triangles, edges and
    nodes as :func:`pseudo_normals` describes (the part's edge and vertex rows zeroed first);
    returns the number of zero-area facets (their normals are left zero). Runs every coupling
    step on every contact surface, so it is one pass without temporaries."""
    tris, edges, nodes = part.triangles, part.edges, part.nodes
    for i in range(edges.shape[0]):
        edge[edges[i], :] = 0.0
    for i in range(nodes.shape[0]):
        vertex[nodes[i], :] = 0.0
    degenerate = 0
    for i in range(tris.shape[0]):
        t = tris[i]
        a, b, c = tri[t, 0], tri[t, 1], tri[t, 2]
        u0, u1, u2 = pts[b, 0] - pts[a, 0], pts[b, 1] - pts[a, 1], pts[b, 2] - pts[a, 2]
        w0, w1, w2 = pts[c, 0] - pts[a, 0], pts[c, 1] - pts[a, 1], pts[c, 2] - pts[a, 2]
        nx = u1 * w2 - u2 * w1
        ny = u2 * w0 - u0 * w2
        nz = u0 * w1 - u1 * w0
        area2 = np.sqrt(nx * nx + ny * ny + nz * nz)
        if area2 <= 0.0:
            degenerate += 1
            face[t, :] = 0.0
            continue
        face[t, 0], face[t, 1], face[t, 2] = nx / area2, ny / area2, nz / area2
        for k in range(3):
            e = tri_edges[t, k]
            edge[e, 0] += face[t, 0]
            edge[e, 1] += face[t, 1]
            edge[e, 2] += face[t, 2]
            # the face's angle at its k-th corner weighs its normal in the vertex's
            node, q, r = tri[t, k], tri[t, (k + 1) % 3], tri[t, (k + 2) % 3]
            q0, q1, q2 = pts[q, 0] - pts[node, 0], pts[q, 1] - pts[node, 1], pts[q, 2] - pts[node, 2]
            r0, r1, r2 = pts[r, 0] - pts[node, 0], pts[r, 1] - pts[node, 1], pts[r, 2] - pts[node, 2]
            cos = ((q0 * r0 + q1 * r1 + q2 * r2)
                   / (np.sqrt(q0 * q0 + q1 * q1 + q2 * q2) * np.sqrt(r0 * r0 + r1 * r1 + r2 * r2)))
            angle = np.arccos(min(1.0, max(-1.0, cos)))
            vertex[node, 0] += angle * face[t, 0]
            vertex[node, 1] += angle * face[t, 1]
            vertex[node, 2] += angle * face[t, 2]
    _normalise(edge, edges)
    _normalise(vertex, nodes)
    return degenerate


@numba.njit(cache=True, inline="always")
def _normalise(rows, which):
    """Scale the rows ``which`` of ``rows`` to unit length (zero rows stay zero)."""
    for j in range(which.shape[0]):
        i = which[j]
        norm = np.sqrt(rows[i, 0] ** 2 + rows[i, 1] ** 2 + rows[i, 2] ** 2)
        if norm > 0.0:
            rows[i, 0] /= norm
            rows[i, 1] /= norm
            rows[i, 2] /= norm


@numba.njit(cache=True, inline="always")
def closest_point_on_triangle(p, a, b, c):
    """Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, 5.1.5).

    Returns ``(u, v, w, feature)``: the barycentric weights of the closest point
    (u a + v b + w c) and the feature it lies on (0 face, 1..3 vertex a, b, c, 4..6 edge ab, bc,
    ca).
    """
    ab0, ab1, ab2 = b[0] - a[0], b[1] - a[1], b[2] - a[2]
    ac0, ac1, ac2 = c[0] - a[0], c[1] - a[1], c[2] - a[2]
    ap0, ap1, ap2 = p[0] - a[0], p[1] - a[1], p[2] - a[2]
    d1 = ab0 * ap0 + ab1 * ap1 + ab2 * ap2
    d2 = ac0 * ap0 + ac1 * ap1 + ac2 * ap2
    if d1 <= 0.0 and d2 <= 0.0:
        return 1.0, 0.0, 0.0, 1
    bp0, bp1, bp2 = p[0] - b[0], p[1] - b[1], p[2] - b[2]
    d3 = ab0 * bp0 + ab1 * bp1 + ab2 * bp2
    d4 = ac0 * bp0 + ac1 * bp1 + ac2 * bp2
    if d3 >= 0.0 and d4 <= d3:
        return 0.0, 1.0, 0.0, 2
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        t = d1 / (d1 - d3)
        return 1.0 - t, t, 0.0, 4
    cp0, cp1, cp2 = p[0] - c[0], p[1] - c[1], p[2] - c[2]
    d5 = ab0 * cp0 + ab1 * cp1 + ab2 * cp2
    d6 = ac0 * cp0 + ac1 * cp1 + ac2 * cp2
    if d6 >= 0.0 and d5 <= d6:
        return 0.0, 0.0, 1.0, 3
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        t = d2 / (d2 - d6)
        return 1.0 - t, 0.0, t, 6
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return 0.0, 1.0 - t, t, 5
    denom = 1.0 / (va + vb + vc)
    v = vb * denom
    w = vc * denom
    return 1.0 - v - w, v, w, FACE
