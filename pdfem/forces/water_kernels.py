"""Numba kernels of the water forces on ice particles (:mod:`pdfem.forces.water`), SI units.

Each particle's cell is a cube of side ``a = vol^(1/3)`` centred on it; its submerged fraction
is ``phi = clip((level - z + a/2) / a, 0, 1)`` (:func:`submerged_fraction`), continuous and
piecewise linear in z. Buoyancy is the force density ``rho_w g phi`` up z (N/m^3); its
potential per unit volume is ``rho_w g Phi(z)`` with ``Phi(z) = integral_z^inf phi`` (m), the
piecewise quadratic :func:`buoyancy_depth`, so the force is exactly minus its gradient. Drag
acts on the relative velocity ``u = v - current`` with the force density
``-phi (rho_ice c_lin + 0.5 rho_w Cd |u| / a) u``.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np


@numba.njit(cache=True, inline="always")
def submerged_fraction(z: float, a: float, level: float) -> float:
    """Submerged fraction (-) of a cube of side ``a`` (m) centred at height ``z`` (m)."""
    phi = (level - z + 0.5 * a) / a
    if phi <= 0.0:
        return 0.0
    if phi >= 1.0:
        return 1.0
    return phi


@numba.njit(cache=True, inline="always")
def buoyancy_depth(z: float, a: float, level: float) -> float:
    """``Phi(z)``, the integral of the submerged fraction from ``z`` up (m): 0 above
    ``level + a/2``, ``(level + a/2 - z)^2 / (2a)`` across the surface, then
    ``a/2 + (level - a/2 - z)`` below it."""
    top = level + 0.5 * a
    if z >= top:
        return 0.0
    bottom = level - 0.5 * a
    if z > bottom:
        return (top - z) ** 2 / (2.0 * a)
    return 0.5 * a + (bottom - z)


class Sea(NamedTuple):
    """The water: surface z ``level`` (m), ``density`` (kg/m^3), gravity magnitude ``g``
    (m/s^2, acting down z), ``current`` (3,) water velocity (m/s), linear drag rate
    ``linear_drag`` (1/s) and quadratic drag coefficient ``drag_coefficient`` (-)."""

    level: float
    density: float
    g: float
    current: np.ndarray
    linear_drag: float
    drag_coefficient: float


@numba.njit(cache=True)
def cell_sides(vol, out):
    """Each particle's cell side ``vol^(1/3)`` (m) into ``out`` ((n,)): the kernels below take
    it from there, a power fewer per particle and call."""
    for i in range(vol.shape[0]):
        out[i] = vol[i] ** (1.0 / 3.0)


@numba.njit(cache=True)
def water_forces(y, v, side, owned, sea, rho_ice, f, drag):
    """Add buoyancy and drag (N/m^3) into ``f`` for the owned particles; write the drag part
    into ``drag`` ((n, 3), zero elsewhere).

    Parameters
    ----------
    y, v
        (n, 3) positions (m) and velocities (m/s).
    side
        (n,) the particles' cell sides ``vol^(1/3)`` (m, :func:`cell_sides`).
    owned
        (n,) uint8, 1 for the particles this rank answers for.
    sea
        The water (:class:`Sea`).
    rho_ice
        Ice density (kg/m^3).
    f, drag
        (n, 3) force density (added into) and the drag force density (written), N/m^3.
    """
    level, rho_w, g, current = sea.level, sea.density, sea.g, sea.current
    c_lin, cd = sea.linear_drag, sea.drag_coefficient
    for i in range(y.shape[0]):
        drag[i, 0] = 0.0
        drag[i, 1] = 0.0
        drag[i, 2] = 0.0
        if owned[i] == 0:
            continue
        a = side[i]
        phi = submerged_fraction(y[i, 2], a, level)
        if phi == 0.0:
            continue
        u0 = v[i, 0] - current[0]
        u1 = v[i, 1] - current[1]
        u2 = v[i, 2] - current[2]
        speed = np.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
        c = phi * (rho_ice * c_lin + 0.5 * rho_w * cd * speed / a)
        drag[i, 0] = -c * u0
        drag[i, 1] = -c * u1
        drag[i, 2] = -c * u2
        f[i, 0] += drag[i, 0]
        f[i, 1] += drag[i, 1]
        f[i, 2] += drag[i, 2] + rho_w * g * phi


@numba.njit(cache=True)
def drag_work(y, y_prev, vol, drag, drag_prev, dissipated, keep_position):
    """Add to ``dissipated`` ((n,) J) minus the drag's work over the last move of each particle,
    by the trapezoid rule: ``-vol (drag_prev + drag) / 2 . (y - y_prev)``, the same rule by
    which velocity Verlet's kicks apply a force over a step; then ``drag_prev = drag`` and,
    with ``keep_position``, ``y_prev = y`` (the next call's start)."""
    for i in range(y.shape[0]):
        w = 0.0
        for k in range(3):
            w += 0.5 * (drag_prev[i, k] + drag[i, k]) * (y[i, k] - y_prev[i, k])
        dissipated[i] -= vol[i] * w
        for k in range(3):
            drag_prev[i, k] = drag[i, k]
            if keep_position:
                y_prev[i, k] = y[i, k]


@numba.njit(cache=True)
def buoyancy_potential(y, x0, vol, side, owned, level, rho_w, g, out):
    """Write into ``out`` ((n,) J) each owned particle's buoyancy potential relative to its
    reference position: ``rho_w g vol (Phi(z) - Phi(z0))`` (0 for the others; ``side``: the
    cell sides, :func:`cell_sides`)."""
    for i in range(y.shape[0]):
        out[i] = 0.0
        if owned[i] == 0:
            continue
        a = side[i]
        out[i] = rho_w * g * vol[i] * (buoyancy_depth(y[i, 2], a, level)
                                        - buoyancy_depth(x0[i, 2], a, level))


@numba.njit(cache=True)
def added_mass_forces(y, side, owned, level, rho_w, rho_ice, ca, gravity, f, am):
    """Give each owned submerged particle the inertia ``rho_ice + ca rho_w phi`` (kg/m^3): its
    acceleration ``(f + rho_ice g) / (rho_ice + ca rho_w phi)`` is what velocity Verlet's kick
    ``f / rho_ice + g`` gives after ``f`` is replaced by ``(f + rho_ice g) s - rho_ice g`` with
    ``s = rho_ice / (rho_ice + ca rho_w phi)``. Call it after every other force is in ``f``;
    the change (the added-mass force density, N/m^3) is written into ``am`` ((n, 3)).
    """
    for i in range(y.shape[0]):
        am[i, 0] = 0.0
        am[i, 1] = 0.0
        am[i, 2] = 0.0
        if owned[i] == 0:
            continue
        phi = submerged_fraction(y[i, 2], side[i], level)
        if phi == 0.0:
            continue
        s = rho_ice / (rho_ice + ca * rho_w * phi)
        for k in range(3):
            am[i, k] = (f[i, k] + rho_ice * gravity[k]) * (s - 1.0)
            f[i, k] += am[i, k]
