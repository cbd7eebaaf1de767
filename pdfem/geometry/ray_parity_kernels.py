"""Numba kernels of the closed-surface point test (:class:`pdfem.geometry.closed_surface.ClosedSurface`).

The triangles are binned into vertical columns of a 2-D grid by their xy bounding boxes
(:func:`bin_triangles`, on :mod:`pdfem.geometry.cell_hash`); a point counts the triangles of its
column crossed by the upward vertical ray (:func:`contains_kernel`), with edge and vertex hits
decided by a consistent symbolic perturbation (:func:`_orient`, :func:`_edge_side`).
"""

from __future__ import annotations

import numba
import numpy as np

from pdfem.geometry.cell_hash import bin_boxes, cell_index


@numba.njit(cache=True)
def _column_boxes(v, t, lo, inv_h, nx, ny, box_lo, box_hi):
    """Column box (i0..i1, j0..j1, 0..0) of every triangle's xy bounding box."""
    for k in range(t.shape[0]):
        a, b, c = t[k, 0], t[k, 1], t[k, 2]
        xmin = min(v[a, 0], v[b, 0], v[c, 0])
        xmax = max(v[a, 0], v[b, 0], v[c, 0])
        ymin = min(v[a, 1], v[b, 1], v[c, 1])
        ymax = max(v[a, 1], v[b, 1], v[c, 1])
        box_lo[k, 0] = cell_index(xmin, lo[0], inv_h[0], nx)
        box_hi[k, 0] = cell_index(xmax, lo[0], inv_h[0], nx)
        box_lo[k, 1] = cell_index(ymin, lo[1], inv_h[1], ny)
        box_hi[k, 1] = cell_index(ymax, lo[1], inv_h[1], ny)
        box_lo[k, 2] = 0
        box_hi[k, 2] = 0


def bin_triangles(v, t, lo, inv_h, nx, ny):
    """CSR (cell_ptr int64, cell_tri int32) of the nx x ny columns -> the triangles whose xy
    bounding box overlaps them, in increasing triangle index per column."""
    box_lo = np.empty((t.shape[0], 3), dtype=np.int64)
    box_hi = np.empty((t.shape[0], 3), dtype=np.int64)
    _column_boxes(v, t, lo, inv_h, nx, ny, box_lo, box_hi)
    cell_ptr = np.zeros(nx * ny + 1, dtype=np.int64)
    cell_tri = np.empty(int(np.prod(box_hi - box_lo + 1, axis=1).sum()), dtype=np.int32)
    bin_boxes(box_lo, box_hi, np.array([nx, ny, 1], dtype=np.int64), cell_ptr, cell_tri)
    return cell_ptr, cell_tri


@numba.njit(cache=True)
def _orient(v, a, b, px, py):
    """orient2d(a, b, p) = (b - a) x (p - anchor) in the xy projection, computed consistently.

    The edge is taken in canonical vertex order (lower index first) and the value negated for the
    reverse edge, and the anchor is whichever end of the edge is nearer to p (a choice that
    depends only on the edge and p), so the two triangles that share an edge see exactly
    opposite values, and near a vertex every edge of its fan is measured from that vertex, where
    p - vertex is exact: the fan's signs agree with each other.
    """
    flip = 1.0
    if a > b:
        a, b = b, a
        flip = -1.0
    ax, ay = v[a, 0], v[a, 1]
    bx, by = v[b, 0], v[b, 1]
    if abs(px - ax) + abs(py - ay) <= abs(px - bx) + abs(py - by):
        w = (bx - ax) * (py - ay) - (by - ay) * (px - ax)
    else:
        w = (bx - ax) * (py - by) - (by - ay) * (px - bx)
    return flip * w


@numba.njit(cache=True)
def _edge_side(v, a, b, px, py):
    """Sign (+1/-1) of :func:`_orient` (a, b, p), never 0 unless a and b coincide in projection.

    A zero is resolved by the symbolic perturbation p -> p + (eps, eps^2), eps -> 0+: the sign of
    d w / d px, else of d w / d py (exact: signs of coordinate differences).
    """
    w = _orient(v, a, b, px, py)
    if w == 0.0:
        w = -(v[b, 1] - v[a, 1])          # d w / d px
        if w == 0.0:
            w = v[b, 0] - v[a, 0]         # d w / d py
    if w > 0.0:
        return 1.0
    if w < 0.0:
        return -1.0
    return 0.0  # a and b coincide in projection: the triangle is degenerate there


@numba.njit(cache=True, parallel=True)
def contains_kernel(x, v, t, origin, inv_h, nx, ny, cell_ptr, cell_tri, lo, hi, out):
    """Vertical ray parity: count triangles hit by the upward ray from each point."""
    n = x.shape[0]
    for p in numba.prange(n):
        px, py, pz = x[p, 0], x[p, 1], x[p, 2]
        if px < lo[0] or py < lo[1] or pz < lo[2] or px > hi[0] or py > hi[1] or pz > hi[2]:
            out[p] = False
            continue
        i = cell_index(px, origin[0], inv_h[0], nx)
        j = cell_index(py, origin[1], inv_h[1], ny)
        cell = i * ny + j
        crossings = 0
        for q in range(cell_ptr[cell], cell_ptr[cell + 1]):
            k = cell_tri[q]
            a, b, c = t[k, 0], t[k, 1], t[k, 2]
            s0 = _edge_side(v, a, b, px, py)
            s1 = _edge_side(v, b, c, px, py)
            s2 = _edge_side(v, c, a, px, py)
            if s0 == 0.0 or s0 != s1 or s1 != s2:
                continue
            # height of the triangle's plane above (px, py) from barycentric weights
            wc = _orient(v, a, b, px, py)
            wa = _orient(v, b, c, px, py)
            wb = _orient(v, c, a, px, py)
            den = wa + wb + wc
            if den == 0.0:
                continue
            z = (wa * v[a, 2] + wb * v[b, 2] + wc * v[c, 2]) / den
            if z > pz:
                crossings += 1
        out[p] = (crossings & 1) == 1
