"""The surface correction of the bond weights on a rank's part of a body.

The correction (:mod:`pdfem.pd.bonds.surface`) iterates per-particle tensors C_i from the second
moments of whole families. A rank has the whole family of each owned particle but not of its
halo particles, so after every iteration the halo's C are overwritten by their owners' values
(``exchange``); the owned particles then see exactly the C the serial iteration gives them. The
loop is the serial kernel's with one chunk (:func:`pdfem.pd.bonds.surface._corrected`, same
arithmetic, same order of the sums per particle), so with one numba thread the weights equal
the global set-up's bit for bit. Dimensionless weights; positions in m, volumes in m^3.
"""

from __future__ import annotations

import numba
import numpy as np

from pdfem.pd.bonds.chunk_kernels import FASTMATH
from pdfem.pd.bonds.surface import _add_moments, _bond_weight, _update_tensor


@numba.njit(cache=True, fastmath=FASTMATH)
def _pass(x, row_ptr, nbr, xi_len, w0, vol, lo, hi, C, M, last, out):
    """One pass of the fixed-point iteration over the rows: moments M (or, if ``last``, the
    corrected weights into ``out``), then the update of C from M."""
    n = row_ptr.shape[0] - 1
    M[:] = 0.0
    for i in range(n):
        for k in range(row_ptr[i], row_ptr[i + 1]):
            j = nbr[k]
            g, aa, bb, cc, ab, ac, bc = _bond_weight(x, i, j, C, xi_len[k], w0[k], lo, hi)
            if last:
                out[k] = g
                continue
            _add_moments(M, i, g * vol[j], aa, bb, cc, ab, ac, bc)
            _add_moments(M, j, g * vol[i], aa, bb, cc, ab, ac, bc)
    if last:
        return
    for i in range(n):
        _update_tensor(C, M, i)


def distributed_surface_weights(x, row_ptr, nbr, xi_len, weight, vol, exchange,
                                iterations: int = 20, bounds=(0.5, 2.0)) -> np.ndarray:
    """Correct the float32 bond weights ``weight`` in place, as
    :func:`pdfem.pd.bonds.surface.surface_corrected_weights` does, the halo's tensors taken from
    their owners with ``exchange`` (a function overwriting the halo rows of a per-particle
    array) after every iteration. Returns ``weight``."""
    n = len(row_ptr) - 1
    C = np.zeros((n, 6))
    M = np.empty((n, 6))
    w0 = weight  # read before written, pair by pair (as the serial kernel with out=weight)
    x = np.ascontiguousarray(x, dtype=np.float64)
    for it in range(iterations + 1):
        last = it == iterations
        _pass(x, row_ptr, nbr, xi_len, w0, vol, float(bounds[0]), float(bounds[1]), C, M, last,
              weight)
        if not last:
            exchange(C)
    return weight
