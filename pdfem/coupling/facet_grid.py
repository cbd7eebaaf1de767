"""Broad phase of contact: a uniform cell hash of surface facets.

Every facet is entered in each cell that its bounding box, grown by a reach, overlaps. A point
then needs to look at the facets of its own cell only: any facet within ``reach`` of the point
is listed there, while no node has moved more than the margin added to the reach since the
build. A grid may hold a part of the facets: the contact keeps one of the facets near the ice
and builds it again with that part, when the surface or the particles have moved the margin
(:mod:`pdfem.coupling.near_facets`); its cells list the facets' numbers in the whole surface. The cells and the cell ->
facets CSR are :mod:`pdfem.geometry.cell_hash`'s (:func:`~pdfem.geometry.cell_hash.bin_boxes`).
Lengths in m.
"""

from __future__ import annotations

import numba
import numpy as np

from pdfem.geometry.cell_hash import bin_boxes, cell_floor


@numba.njit(cache=True)
def _cell_ranges(points, triangles, reach, origin, inv_h, dims, lo, hi):
    """Cell box (lo, hi inclusive, clamped to the grid) of every facet's grown bounding box."""
    for f in range(triangles.shape[0]):
        for d in range(3):
            a = points[triangles[f, 0], d]
            b = points[triangles[f, 1], d]
            c = points[triangles[f, 2], d]
            mn = min(a, min(b, c)) - reach
            mx = max(a, max(b, c)) + reach
            lo[f, d] = max(0, cell_floor(mn, origin[d], inv_h))
            hi[f, d] = min(dims[d] - 1, cell_floor(mx, origin[d], inv_h))


class FacetGrid:
    """Cell hash of the facets of one surface.

    Parameters
    ----------
    triangles
        (T, 3) int32 node indices.
    reach
        Distance (m) within which a point must find every nearby facet (the contact search
        radius).
    margin
        Extra reach (m); the grid stays valid until some node has moved this far since the
        last build. Default: ``reach``.
    cell_size
        Cell edge (m). Default: the larger of 2 (reach + margin) and the median facet edge
        of the whole surface (at the first build; a grid of a part of the facets keeps the
        cells the whole surface's would have).
    """

    def __init__(self, triangles: np.ndarray, reach: float, margin: float | None = None,
                 cell_size: float | None = None) -> None:
        if not reach > 0.0:
            raise ValueError(f"reach must be > 0, got {reach}")
        self.triangles = np.ascontiguousarray(triangles, dtype=np.int32)
        self.reach = float(reach)
        self.margin = float(reach if margin is None else margin)
        self._cell_size = cell_size
        self._median_edge: float | None = None
        self.builds = 0

    def build(self, points: np.ndarray, facets: np.ndarray | None = None) -> None:
        """(Re)build the hash for node positions ``points`` ((Ns, 3), m), of the facets
        ``facets`` (ascending int32 facet numbers; default all): the cells list facet numbers
        of the whole surface. Without facets the grid is one empty cell."""
        points = np.ascontiguousarray(points, dtype=np.float64)
        facets = (np.arange(len(self.triangles), dtype=np.int32) if facets is None
                  else np.ascontiguousarray(facets, dtype=np.int32))
        triangles = self.triangles[facets]
        grow = self.reach + self.margin
        h = self._cell_size
        if h is None:
            if self._median_edge is None:
                x = points[self.triangles]
                edges = np.linalg.norm(x - np.roll(x, 1, axis=1), axis=2)
                self._median_edge = float(np.median(edges))
            h = max(2.0 * grow, self._median_edge)
        nodes = points[triangles].reshape(-1, 3) if len(facets) else points[:1]
        lo_box = nodes.min(axis=0) - grow
        hi_box = nodes.max(axis=0) + grow
        dims = np.maximum(1, np.ceil((hi_box - lo_box) / h).astype(np.int64))
        while np.prod(dims) > 8 * len(self.triangles) + 1000:  # the whole surface's bound
            h *= 1.5
            dims = np.maximum(1, np.ceil((hi_box - lo_box) / h).astype(np.int64))
        self.origin = lo_box
        self.inv_h = 1.0 / h
        self.dims = dims
        nt = len(facets)
        lo = np.empty((nt, 3), dtype=np.int64)
        hi = np.empty((nt, 3), dtype=np.int64)
        _cell_ranges(points, triangles, grow, self.origin, self.inv_h, self.dims, lo, hi)
        count = int(np.prod(hi - lo + 1, axis=1).sum())
        self.cell_start = np.zeros(int(np.prod(dims)) + 1, dtype=np.int64)
        local = np.empty(count, dtype=np.int32)
        bin_boxes(lo, hi, self.dims, self.cell_start, local)
        self.cell_facets = facets[local]
        self.builds += 1
