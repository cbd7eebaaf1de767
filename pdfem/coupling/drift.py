"""The ice's drift over one structure substep of a coupling step, in one pass over the particles.

Within a coupling step of D split into n structure substeps of h = D / n, each substep moves
the particles by ``h u`` with the velocity of that substep, ``u = v + kick c`` (``kick`` the
first half kick D/2 a_t, ``c = (2 j + 1) / n - 1`` for substep j; ``u = v`` when n = 1), and
the contact then needs the positions before the move. :func:`drift` does the three in one pass
(the copy, the velocity and the move), with numpy's operations and order: the same bits as
``before = y.copy(); u = v + kick * c; y += h * u``. Called as ``drift(parallel, ...)``
(:func:`pdfem.parallel.kernels.twin`): threaded for large bodies, else on one thread. Units: m, m/s, s.
"""

from __future__ import annotations

from numba import prange

from pdfem.parallel.kernels import twin


@twin(fastmath=False)
def drift(y, v, kick, c, h, before, u, with_kick, keep_before):
    """Move ``y`` (n, 3) by ``h u`` in place, ``u = v + kick * c`` if ``with_kick`` (written to
    ``u``) else ``v`` (``u`` untouched); the positions before the move go to ``before`` if
    ``keep_before``."""
    for i in prange(y.shape[0]):
        for k in range(3):
            if keep_before:
                before[i, k] = y[i, k]
            if with_kick:
                w = v[i, k] + kick[i, k] * c
                u[i, k] = w
            else:
                w = v[i, k]
            y[i, k] += h * w
