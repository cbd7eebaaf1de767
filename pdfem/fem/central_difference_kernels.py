"""The central-difference step's two vector passes (numba), around its ``K u`` product.

:meth:`pdfem.fem.explicit.CentralDifference.step` is ``predict``, then ``K u_new`` (node
blocks, :mod:`pdfem.fem.node_blocks`), then ``correct``: two passes over the DOF vectors instead
of a dozen numpy operations with their temporaries (a structure substep's Python was about as
long as its product on the demo panel's 13,980 DOFs). Each pass does numpy's operations in
numpy's order, without fused multiply-adds: the same bits as the vector form in the module
docstring of :mod:`pdfem.fem.explicit`. Units: m, m/s, m/s^2, N, kg, s.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def predict(u, v, a, dt, fixed, g, v_half, u_new):
    """``v_half = v + dt/2 a``, ``u_new = u + dt v_half``; on the Dirichlet DOFs ``fixed``
    the prescribed displacement ``g`` at the new time: ``v_half = (g - u) / dt``, ``u_new = g``."""
    half = 0.5 * dt
    for i in range(u.shape[0]):
        vh = v[i] + half * a[i]
        v_half[i] = vh
        u_new[i] = u[i] + dt * vh
    for k in range(fixed.shape[0]):
        i = fixed[k]
        v_half[i] = (g[k] - u[i]) / dt
        u_new[i] = g[k]


@numba.njit(cache=True)
def correct(f, ku, f_damp, damped, m, dt, v_half, v_half_old, fixed, a_new, v):
    """``a_new = (f - ku - f_damp) / m`` (``f_damp`` only if ``damped``), on the Dirichlet DOFs
    ``(v_half - v_half_old) / dt``; ``v = v_half + dt/2 a_new``, ``v_half`` on the Dirichlet DOFs."""
    for i in range(f.shape[0]):
        x = f[i] - ku[i]
        if damped:
            x -= f_damp[i]
        a_new[i] = x / m[i]
    for k in range(fixed.shape[0]):
        i = fixed[k]
        a_new[i] = (v_half[i] - v_half_old[i]) / dt
    half = 0.5 * dt
    for i in range(f.shape[0]):
        v[i] = v_half[i] + half * a_new[i]
    for k in range(fixed.shape[0]):
        i = fixed[k]
        v[i] = v_half[i]


NO_OFFSET = np.zeros(0)
"""The ``u0`` of :func:`trapezoid_work` when ``du`` is the increment itself."""
NO_OFFSET.flags.writeable = False


@numba.njit(cache=True)
def trapezoid_work(f0, f1, du, u0):
    """``1/2 (f0 + f1) . du`` (J), or with ``u0`` of the same length ``1/2 (f0 + f1) . (du -
    u0)`` (``du`` then the new displacement, ``u0`` the old): the work of a force over a step
    by the trapezoidal rule, in one pass without temporaries and without BLAS (whose threads'
    start-up cost more than a structure's dot product; four partial sums)."""
    diff = u0.shape[0] == du.shape[0]
    n = f0.shape[0]
    s0 = s1 = s2 = s3 = 0.0
    m = n - n % 4
    for i in range(0, m, 4):
        if diff:
            s0 += (f0[i] + f1[i]) * (du[i] - u0[i])
            s1 += (f0[i + 1] + f1[i + 1]) * (du[i + 1] - u0[i + 1])
            s2 += (f0[i + 2] + f1[i + 2]) * (du[i + 2] - u0[i + 2])
            s3 += (f0[i + 3] + f1[i + 3]) * (du[i + 3] - u0[i + 3])
        else:
            s0 += (f0[i] + f1[i]) * du[i]
            s1 += (f0[i + 1] + f1[i + 1]) * du[i + 1]
            s2 += (f0[i + 2] + f1[i + 2]) * du[i + 2]
            s3 += (f0[i + 3] + f1[i + 3]) * du[i + 3]
    for i in range(m, n):
        s0 += (f0[i] + f1[i]) * (du[i] - u0[i] if diff else du[i])
    return 0.5 * ((s0 + s1) + (s2 + s3))
