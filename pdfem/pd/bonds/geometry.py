"""Bond pairs of an ice body: the unique pairs i<j grouped by i, and their reference lengths.

The family of every particle is fixed at t = 0 (bonds only break), so the pairs are built once
per body by the cell search (:func:`pdfem.pd.bonds.search.cell_pairs`) and stored as a CSR-like list:
``row_ptr`` (int64, N+1) and ``nbr`` (int32, P) -- the seed paper's "particle-pair" array.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True, parallel=True)
def bond_lengths(x: np.ndarray, row_ptr: np.ndarray, nbr: np.ndarray) -> np.ndarray:
    """Reference length |x_j - x_i| (m) of every unique pair, in pair order."""
    n = x.shape[0]
    out = np.empty(nbr.shape[0], dtype=np.float64)
    for i in numba.prange(n):
        xi0, xi1, xi2 = x[i, 0], x[i, 1], x[i, 2]
        for k in range(row_ptr[i], row_ptr[i + 1]):
            j = nbr[k]
            d0 = x[j, 0] - xi0
            d1 = x[j, 1] - xi1
            d2 = x[j, 2] - xi2
            out[k] = np.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
    return out


@numba.njit(cache=True)
def cut_crack(x: np.ndarray, row_ptr: np.ndarray, nbr: np.ndarray, broken: np.ndarray,
              point: np.ndarray, normal: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> int:
    """Break every bond that crosses a planar pre-crack.

    The crack lies in the plane through ``point`` with ``normal``; it is the part of that plane
    inside the axis-aligned box ``[lo, hi]``. A bond crosses it when its ends lie strictly on
    opposite sides of the plane and the crossing point is inside the box.

    Returns
    -------
    int
        The number of bonds cut.
    """
    n = row_ptr.shape[0] - 1
    count = 0
    for i in range(n):
        si = 0.0
        for c in range(3):
            si += (x[i, c] - point[c]) * normal[c]
        for k in range(row_ptr[i], row_ptr[i + 1]):
            j = nbr[k]
            sj = 0.0
            for c in range(3):
                sj += (x[j, c] - point[c]) * normal[c]
            if si * sj >= 0.0:
                continue
            t = si / (si - sj)
            inside = True
            for c in range(3):
                xc = x[i, c] + t * (x[j, c] - x[i, c])
                if xc < lo[c] or xc > hi[c]:
                    inside = False
            if inside and broken[k] == 0:
                broken[k] = 1
                count += 1
    return count
