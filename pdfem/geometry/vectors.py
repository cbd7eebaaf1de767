"""Small-vector arithmetic for the per-step work of moving frames, rigid bodies and contact.

:func:`cross` is ``numpy.cross`` for 3-vectors without its axis handling: the same products
and differences, so the same bits, at a fraction of the cost on the small arrays of a step
(``numpy.cross`` spends most of a (3,) product in ``moveaxis`` and argument checks, a numpy
expression of the components still 13 us in broadcasting and temporaries; the propeller's
blade substeps call it about 900,000 times a revolution). The rows are computed by a numba
kernel: (3,) and (N, 3) operands in any combination. :func:`resultant` sums forces and their
moments in one pass, as ``sum(axis=0)`` of the rows and of their ``cross`` products would.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def _cross_rows(a, b, out):
    """``out[i] = a[i] x b[i]`` for (n, 3) or (1, 3) ``a`` and ``b`` (a single row is
    broadcast), as numpy writes the components."""
    ia, ib = a.shape[0] > 1, b.shape[0] > 1
    for i in range(out.shape[0]):
        p, q = a[i if ia else 0], b[i if ib else 0]
        out[i, 0] = p[1] * q[2] - p[2] * q[1]
        out[i, 1] = p[2] * q[0] - p[0] * q[2]
        out[i, 2] = p[0] * q[1] - p[1] * q[0]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` over the last axis (length 3), broadcasting the others as ``numpy.cross``.

    Parameters
    ----------
    a, b
        Arrays whose last axis has length 3, e.g. (3,) and (N, 3).

    Returns
    -------
    numpy.ndarray
        ``a1 b2 - a2 b1, a2 b0 - a0 b2, a0 b1 - a1 b0`` along the last axis, float64.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.ndim <= 2 and b.ndim <= 2:
        a2, b2 = a.reshape(-1, 3), b.reshape(-1, 3)
        n = max(a2.shape[0], b2.shape[0])
        if a2.shape[0] in (1, n) and b2.shape[0] in (1, n):
            out = np.empty((n, 3))
            _cross_rows(a2, b2, out)
            return out if max(a.ndim, b.ndim) == 2 else out[0]
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a1 * b2 - a2 * b1
    out[..., 1] = a2 * b0 - a0 * b2
    out[..., 2] = a0 * b1 - a1 * b0
    return out


@numba.njit(cache=True)
def _resultant(points, forces, out):
    for i in range(points.shape[0]):
        f0, f1, f2 = forces[i, 0], forces[i, 1], forces[i, 2]
        if f0 == 0.0 and f1 == 0.0 and f2 == 0.0:
            continue  # adds (+-)0 to both sums
        p0, p1, p2 = points[i, 0], points[i, 1], points[i, 2]
        out[0, 0] += f0
        out[0, 1] += f1
        out[0, 2] += f2
        out[1, 0] += p1 * f2 - p2 * f1
        out[1, 1] += p2 * f0 - p0 * f2
        out[1, 2] += p0 * f1 - p1 * f0


def resultant(points: np.ndarray, forces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sum of the rows of ``forces`` and of their moments ``points x forces`` about the origin.

    The rows are added in order, as ``forces.sum(axis=0)`` and ``cross(points,
    forces).sum(axis=0)`` add them, so the same bits (rows of zeros, which add only zeros, are
    skipped; the sums start from +0).

    Parameters
    ----------
    points
        (N, 3) points of application (m).
    forces
        (N, 3) forces (N) or impulses (N s).

    Returns
    -------
    force, moment
        (3,) each: the sum of the forces and of their moments (N m, or N s m).
    """
    out = np.zeros((2, 3))
    _resultant(np.ascontiguousarray(points, dtype=np.float64),
               np.ascontiguousarray(forces, dtype=np.float64), out)
    return out[0], out[1]
