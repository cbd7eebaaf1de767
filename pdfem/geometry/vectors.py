"""Small-vector arithmetic for the per-step work of moving frames, rigid bodies and contact.

:func:`cross` is ``numpy.cross`` for 3-vectors without its axis handling: the same products
and differences, so the same bits, at a fraction of the cost on the small arrays of a step
(``numpy.cross`` spends most of a (3,) product in ``moveaxis`` and argument checks; the
propeller's blade substeps called it about 900,000 times a revolution).
"""

from __future__ import annotations

import numpy as np


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
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a1 * b2 - a2 * b1
    out[..., 1] = a2 * b0 - a0 * b2
    out[..., 2] = a0 * b1 - a1 * b0
    return out
