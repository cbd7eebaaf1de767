"""Velocity-Verlet half steps over particle arrays (numba): the kick and the drift.

A step of the explicit time loop is ``kick(dt/2); drift(dt); forces; kick(dt/2)``. Both loops
write only their own particle's entries, so they thread without races; below
``SERIAL_BELOW_STREAMING`` particles they run on one thread. :func:`set_rows` and
:func:`place_rows` put prescribed velocities and positions on a region's rows.
"""

from __future__ import annotations

import numba
import numpy as np
from numba import prange

from pdfem.parallel.kernels import twin
from pdfem.parallel.kernels import SERIAL_BELOW_STREAMING

@twin(fastmath=False)
def _kick(v, f, inv_rho, half_dt, g, free):
    uniform = inv_rho.shape[0] == 1
    all_free = free.shape[0] == 0
    for i in prange(v.shape[0]):
        if all_free or free[i] != 0:
            ir = inv_rho[0] if uniform else inv_rho[i]
            v[i, 0] += half_dt * (f[i, 0] * ir + g[0])
            v[i, 1] += half_dt * (f[i, 1] * ir + g[1])
            v[i, 2] += half_dt * (f[i, 2] * ir + g[2])


@twin(fastmath=False)
def _drift(y, v, dt):
    for i in prange(y.shape[0]):
        y[i, 0] += dt * v[i, 0]
        y[i, 1] += dt * v[i, 1]
        y[i, 2] += dt * v[i, 2]


@numba.njit(cache=True)
def set_rows(a, rows, value):
    """``a[rows] = value`` ((n, 3) array, (k,) rows, (3,) value), as numpy assigns it."""
    for t in range(rows.shape[0]):
        i = rows[t]
        a[i, 0] = value[0]
        a[i, 1] = value[1]
        a[i, 2] = value[2]


@numba.njit(cache=True)
def place_rows(y, x0, rows, u):
    """``y[rows] = x0[rows] + u`` ((n, 3) arrays, (k,) rows, (3,) displacement), as numpy
    computes it (one rounding per entry)."""
    for t in range(rows.shape[0]):
        i = rows[t]
        y[i, 0] = x0[i, 0] + u[0]
        y[i, 1] = x0[i, 1] + u[1]
        y[i, 2] = x0[i, 2] + u[2]


def verlet_kick(
    v: np.ndarray,
    f: np.ndarray,
    inv_rho: float | np.ndarray,
    half_dt: float,
    gravity: np.ndarray | tuple[float, float, float] = (0.0, 0.0, 0.0),
    free_mask: np.ndarray | None = None,
) -> None:
    """Velocity half step of velocity Verlet, in place: ``v += half_dt * (f / rho + g)``.

    Parameters
    ----------
    v
        (N, 3) velocities (m/s), updated in place.
    f
        (N, 3) force density (N/m^3).
    inv_rho
        1 / density (m^3/kg), a scalar or (N,) array.
    half_dt
        The velocity increment's time step, normally dt / 2 (s).
    gravity
        (3,) body acceleration (m/s^2).
    free_mask
        Optional (N,) uint8/bool: particles with 0 keep their velocity (prescribed motion).
    """
    ir = np.atleast_1d(np.asarray(inv_rho, dtype=np.float64))
    g = np.asarray(gravity, dtype=np.float64).reshape(3)
    if free_mask is None:
        free = np.zeros(0, dtype=np.uint8)
    else:
        free = np.ascontiguousarray(free_mask).view(np.uint8)
    _kick(v.shape[0] >= SERIAL_BELOW_STREAMING, v, f, ir, float(half_dt), g, free)


def verlet_drift(y: np.ndarray, v: np.ndarray, dt: float) -> None:
    """Position update of velocity Verlet, in place: ``y += dt * v`` (m, m/s, s)."""
    _drift(y.shape[0] >= SERIAL_BELOW_STREAMING, y, v, float(dt))
