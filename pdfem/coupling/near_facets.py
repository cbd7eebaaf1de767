"""The part of a contact surface near the ice: the facets a particle can reach, kept with a skin.

Only a facet within the search radius (the reach) of a particle can take part in a contact, so
the work a surface needs as it moves (its pseudo-normals, :mod:`pdfem.coupling.facets`; its
facet grid, :mod:`pdfem.coupling.facet_grid`) is needed only near the particles. A milling
propeller's block touches one blade at a time; a hull's ice lies along a strip of it.

:class:`NearFacets` selects, for the node positions ``X0`` and particle positions ``Y0`` of its
last build:

* the *near* facets: those whose bounding box, grown by ``reach + 2 skin``, overlaps a cell of
  side ``h >= reach + 2 skin`` that holds a particle (a superset of the facets whose grown box
  holds a particle). The selection is kept while no node has moved more than the skin from
  ``X0`` and no particle more than the skin from ``Y0``: then a particle within reach of a
  facet lies in the facet's box of now grown by the reach, which lies in its box at the build
  grown by ``reach + skin``, and the particle's position at the build in that box grown by
  ``reach + 2 skin``, so the facet is near (the particles counted as a set: a renumbering of
  the particles keeps the argument);
* the *part* whose pseudo-normals are computed: the near facets and every facet sharing a node
  with them (hence every facet around each of their edges and vertices), with their edges and
  nodes. The pseudo-normal of a near facet's edge or vertex sums the normals of every facet
  around it, in ascending facet order, as the whole surface's pass does: the same numbers, bit
  for bit (:func:`pdfem.coupling.facets.pseudo_normals_of`).

The cells of the particles are counted once per build into a summed-volume table, so that a
facet's box asks 8 entries, whatever its size. A build costs one pass over the facets and the
particles; between builds a check costs one pass over the displacements of the nodes and the
particles (the broad phase's pattern, :mod:`pdfem.coupling.broad_phase`). Units: m.
"""

from __future__ import annotations

import numba
import numpy as np

from pdfem.coupling.broad_phase import moved_beyond
from pdfem.coupling.facets import FacetPart, FacetTopology
from pdfem.geometry.cell_hash import bounding_box, cell_floor, cell_id


@numba.njit(cache=True, inline="always")
def _clamped(p, lo, inv_h, n):
    """Cell coordinate ``floor((p - lo) inv_h)`` of ``p``, clamped to [-1, n]."""
    c = cell_floor(max(lo - 1.0 / inv_h, min(p, lo + (n + 1.0) / inv_h)), lo, inv_h)
    return min(n, max(-1, c))


@numba.njit(cache=True)
def _occupancy(y, lo, inv_h, dims, table):
    """Summed-volume table ``table`` ((nx + 1) (ny + 1) (nz + 1) int64, zeros on entry) of the
    count of particles ``y`` (in the box of the cells) per cell: entry (i, j, k) counts the
    particles of the cells (i', j', k') < (i, j, k)."""
    sy, sz = dims[1] + 1, dims[2] + 1
    for p in range(y.shape[0]):
        i = min(dims[0] - 1, max(0, _clamped(y[p, 0], lo[0], inv_h, dims[0])))
        j = min(dims[1] - 1, max(0, _clamped(y[p, 1], lo[1], inv_h, dims[1])))
        k = min(dims[2] - 1, max(0, _clamped(y[p, 2], lo[2], inv_h, dims[2])))
        table[cell_id(i + 1, j + 1, k + 1, sy, sz)] += 1
    for i in range(1, dims[0] + 1):
        for j in range(1, dims[1] + 1):
            for k in range(1, dims[2] + 1):
                table[cell_id(i, j, k, sy, sz)] += (
                    table[cell_id(i - 1, j, k, sy, sz)] + table[cell_id(i, j - 1, k, sy, sz)]
                    + table[cell_id(i, j, k - 1, sy, sz)] - table[cell_id(i - 1, j - 1, k, sy, sz)]
                    - table[cell_id(i - 1, j, k - 1, sy, sz)]
                    - table[cell_id(i, j - 1, k - 1, sy, sz)]
                    + table[cell_id(i - 1, j - 1, k - 1, sy, sz)])


@numba.njit(cache=True, inline="always")
def _cells(points, tri, f, d, grow, lo, inv_h, n):
    """The cells ``(first, last + 1)`` along axis ``d``, clamped to [0, n], that facet f's
    bounding box grown by ``grow`` (m) overlaps (empty when first >= last + 1)."""
    a = points[tri[f, 0], d]
    b = points[tri[f, 1], d]
    c = points[tri[f, 2], d]
    first = max(0, _clamped(min(a, min(b, c)) - grow, lo, inv_h, n))
    last = min(n - 1, _clamped(max(a, max(b, c)) + grow, lo, inv_h, n))
    return first, max(first, last + 1)


@numba.njit(cache=True)
def _near(points, triangles, grow, lo, inv_h, dims, table, near):
    """``near[f]``: whether facet f's bounding box grown by ``grow`` (m) overlaps a cell of
    the table (:func:`_occupancy`) that holds a particle."""
    sy, sz = dims[1] + 1, dims[2] + 1
    for f in range(triangles.shape[0]):
        i0, i1 = _cells(points, triangles, f, 0, grow, lo[0], inv_h, dims[0])
        j0, j1 = _cells(points, triangles, f, 1, grow, lo[1], inv_h, dims[1])
        k0, k1 = _cells(points, triangles, f, 2, grow, lo[2], inv_h, dims[2])
        count = (table[cell_id(i1, j1, k1, sy, sz)] - table[cell_id(i0, j1, k1, sy, sz)]
                 - table[cell_id(i1, j0, k1, sy, sz)] - table[cell_id(i1, j1, k0, sy, sz)]
                 + table[cell_id(i0, j0, k1, sy, sz)] + table[cell_id(i0, j1, k0, sy, sz)]
                 + table[cell_id(i1, j0, k0, sy, sz)] - table[cell_id(i0, j0, k0, sy, sz)])
        near[f] = count > 0


@numba.njit(cache=True)
def _either_moved(points, points0, y, y0, skin):
    """Whether a node of ``points`` or a particle of ``y`` lies more than ``skin`` (m) from
    its position in ``points0``, ``y0`` (one call for both: this runs every substep)."""
    return moved_beyond(points, points0, skin) or moved_beyond(y, y0, skin)


@numba.njit(cache=True)
def _around(near, triangles, node_start, node_facets, part):
    """``part[f]``: whether facet f is near or shares a node with a near facet."""
    for f in range(triangles.shape[0]):
        if not near[f]:
            continue
        for k in range(3):
            n = triangles[f, k]
            for s in range(node_start[n], node_start[n + 1]):
                part[node_facets[s]] = True


class NearFacets:
    """The facets of a surface near the particles, and the part whose normals they need
    (module docstring).

    Parameters
    ----------
    topology
        The surface's :class:`pdfem.coupling.facets.FacetTopology`.
    n_nodes
        Number of surface nodes Ns.
    reach
        Distance (m) within which a particle takes part in a contact (the search radius).
    skin
        How far (m) the nodes or the particles may move before the selection is made again.

    Attributes
    ----------
    facets
        (F,) int32 near facets, ascending.
    part
        The :class:`pdfem.coupling.facets.FacetPart` of the near facets and the facets around
        them.
    builds
        How many times the selection was made.
    """

    def __init__(self, topology: FacetTopology, n_nodes: int, reach: float,
                 skin: float) -> None:
        if not (reach > 0.0 and skin > 0.0):
            raise ValueError(f"reach and skin must be > 0, got {reach}, {skin}")
        self.topology = topology
        self.reach, self.skin = float(reach), float(skin)
        tri = topology.triangles
        order = np.argsort(tri.ravel(), kind="stable")
        self._node_facets = (order // 3).astype(np.int32)
        self._node_start = np.zeros(n_nodes + 1, dtype=np.int64)
        np.cumsum(np.bincount(tri.ravel(), minlength=n_nodes), out=self._node_start[1:])
        self.facets = np.zeros(0, dtype=np.int32)
        empty = np.zeros(0, dtype=np.int32)
        self.part = FacetPart(empty, empty, empty)
        self.builds = 0
        self._points: np.ndarray | None = None
        self._y: np.ndarray | None = None

    def valid(self, points: np.ndarray, y: np.ndarray) -> bool:
        """Whether the selection holds for nodes at ``points`` ((Ns, 3), m) and particles at
        ``y`` ((N, 3), m): made, for as many particles, and neither has moved more than the
        skin since."""
        return not (self._points is None or self._y.shape != y.shape
                    or _either_moved(points, self._points, y, self._y, self.skin))

    def build(self, points: np.ndarray, y: np.ndarray) -> None:
        """Select the facets near the particles ``y`` ((N, 3), m) for nodes at ``points``
        ((Ns, 3), m), both float64 and C-contiguous. Particles with a coordinate that is not
        finite select every facet."""
        tri = self.topology.triangles
        grow = (self.reach + 2.0 * self.skin) * (1.0 + 1e-9)    # (rounding of the boxes)
        near = np.zeros(len(tri), dtype=np.bool_)
        if len(y):
            lo, hi, finite = bounding_box(y)
            if not finite:
                near[:] = True
            else:
                h = grow
                while True:   # the particles' cells, floor((y - lo) / h), are < dims
                    dims = np.floor((hi - lo) * (1.0 / h)).astype(np.int64) + 1
                    if np.prod(dims + 1) <= 8 * len(y) + 1000:    # keep the table small
                        break
                    h *= 1.5
                table = np.zeros(int(np.prod(dims + 1)), dtype=np.int64)
                _occupancy(y, lo, 1.0 / h, dims, table)
                _near(points, tri, grow, lo, 1.0 / h, dims, table, near)
        part = np.zeros(len(tri), dtype=np.bool_)
        _around(near, tri, self._node_start, self._node_facets, part)
        self.facets = np.flatnonzero(near).astype(np.int32)
        facets = np.flatnonzero(part).astype(np.int32)
        self.part = FacetPart(facets, np.unique(self.topology.tri_edges[facets]).astype(np.int32),
                              np.unique(tri[facets]).astype(np.int32))
        self._points = points.copy()
        self._y = y.copy()
        self.builds += 1
