"""Hydrostatic pressure on a closed triangulated hull, integrated exactly over the part of each
triangle below the still water surface (no linearisation), SI units (m, N, N m, J).

The pressure ``p = rho g (level - z)`` is linear on a triangle, so after clipping each triangle
at ``z = level`` (one submerged corner: a triangle; two: a quadrilateral split in two) the
integrals are exact: for a triangle of area A with corner values ``d_i`` of the depth,
``int d dA = A (d_1 + d_2 + d_3) / 3``, ``int d x dA = A / 12 (sum d_i x_i + sum d_i sum x_i)``
and ``int d^2 dA = A / 12 (sum d_i^2 + (sum d_i)^2)``. With n the outward normal the force on
the hull is ``F = -rho g int d n dA`` (buoyancy), its moment about ``c`` is
``M = -rho g int d (x - c) x n dA``, and the hydrostatic potential energy of the submerged
volume ``U = rho g int_V (level - z) dV = -rho g / 2 int d^2 n_z dA`` (divergence theorem; the
cut at the waterplane contributes nothing as d = 0 there). ``-dU/dz`` of a translation is the
buoyancy ``rho g V_submerged``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from pdfem.geometry.vectors import cross
from pdfem.motion.rotation import rotation_matrix


@dataclass
class Hydrostatics:
    """Result of :func:`hydrostatics` (SI)."""

    force: np.ndarray        # (3,) N, on the hull
    moment: np.ndarray       # (3,) N m, about the centre given
    potential: float         # J, rho g int_V (level - z) dV
    volume: float            # m^3, submerged volume
    centre_of_buoyancy: np.ndarray  # (3,) m (the centre given if nothing is submerged)


@numba.njit(cache=True)
def _wet_parts(x, tri, level, p, d):
    """Fill ``p`` (K, 3, 3) and ``d`` (K, 3) with the submerged parts of the triangles and
    return K. Order: the wholly wet triangles, the one-corner triangles, then the first and
    then the second halves of the two-corner quadrilaterals (each group in triangle order).
    Each partly wet triangle is turned cyclically so that its odd corner (the wet one of one,
    the dry one of two) comes first, which keeps its orientation; the waterline crossings are
    ``a + (d_a / (d_a - d_b)) (b - a)``, as the numpy expression this kernel replaced."""
    nt = tri.shape[0]
    depth = np.empty((nt, 3))
    count = np.zeros(nt, dtype=np.int64)
    for t in range(nt):
        for k in range(3):
            depth[t, k] = level - x[tri[t, k], 2]
            if depth[t, k] > 0.0:
                count[t] += 1
    m = 0
    for t in range(nt):
        if count[t] == 3:
            for k in range(3):
                for c in range(3):
                    p[m, k, c] = x[tri[t, k], c]
                d[m, k] = depth[t, k]
            m += 1
    for group in range(3):           # one wet corner; two (first halves); two (second halves)
        wet_corners = 1 if group == 0 else 2
        for t in range(nt):
            if count[t] != wet_corners:
                continue
            first = 0
            for k in range(3):
                if (depth[t, k] > 0.0) == (wet_corners == 1):
                    first = k
                    break
            ia, ib, ic = tri[t, first], tri[t, (first + 1) % 3], tri[t, (first + 2) % 3]
            da, db, dc = depth[t, first], depth[t, (first + 1) % 3], depth[t, (first + 2) % 3]
            fb, fc = da / (da - db), da / (da - dc)
            for c in range(3):
                a, b, cc = x[ia, c], x[ib, c], x[ic, c]
                ab, ac = a + fb * (b - a), a + fc * (cc - a)
                if group == 0:
                    p[m, 0, c], p[m, 1, c], p[m, 2, c] = a, ab, ac
                elif group == 1:
                    p[m, 0, c], p[m, 1, c], p[m, 2, c] = ab, b, cc
                else:
                    p[m, 0, c], p[m, 1, c], p[m, 2, c] = ab, cc, ac
            if group == 0:
                d[m, 0], d[m, 1], d[m, 2] = da, 0.0, 0.0
            elif group == 1:
                d[m, 0], d[m, 1], d[m, 2] = 0.0, db, dc
            else:
                d[m, 0], d[m, 1], d[m, 2] = 0.0, dc, 0.0
            m += 1
    return m


def _wet_triangles(x: np.ndarray, tri: np.ndarray, level: float) -> tuple[np.ndarray, np.ndarray]:
    """Corners (K, 3, 3) (m) and depths (K, 3) (m, >= 0) of the submerged parts of the
    triangles, with the triangles' orientation kept (:func:`_wet_parts`)."""
    tri = np.ascontiguousarray(tri, dtype=np.int64)
    p = np.empty((2 * len(tri), 3, 3))
    d = np.empty((2 * len(tri), 3))
    k = _wet_parts(np.ascontiguousarray(x, dtype=np.float64), tri, level, p, d)
    return p[:k], d[:k]


def hydrostatics(x: np.ndarray, triangles: np.ndarray, level: float, density: float, g: float,
                 about) -> Hydrostatics:
    """Hydrostatic force, moment, potential energy and submerged volume of a closed hull.

    Parameters
    ----------
    x
        (N, 3) node positions (m), current pose.
    triangles
        (T, 3) outward-oriented triangles of the closed hull surface.
    level
        z of the still water surface (m).
    density
        Water density (kg/m^3).
    g
        Gravity magnitude (m/s^2), acting down z.
    about
        (3,) point (m) the moment is taken about (the centre of gravity).
    """
    c = np.asarray(about, dtype=np.float64).reshape(3)
    p, d = _wet_triangles(np.asarray(x, dtype=np.float64), np.asarray(triangles), float(level))
    if len(p) == 0:
        return Hydrostatics(np.zeros(3), np.zeros(3), 0.0, 0.0, c.copy())
    area_n = 0.5 * cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])  # A n, (K, 3)
    sd = d.sum(axis=1)
    # int d dA = A sd / 3; with area_n = A n: int d n dA = area_n sd / 3
    f = -density * g * (area_n * (sd / 3.0)[:, None]).sum(axis=0)
    r = p - c
    dx = (d[:, :, None] * r).sum(axis=1) + sd[:, None] * r.sum(axis=1)  # 12 int d r dA / A
    m = -density * g * (cross(dx, area_n) / 12.0).sum(axis=0)
    d2 = (d * d).sum(axis=1) + sd * sd                            # 12 int d^2 dA / A
    u = -0.5 * density * g * float((area_n[:, 2] * d2 / 12.0).sum())
    volume = -float((area_n[:, 2] * sd / 3.0).sum())              # int d n_z dA = -V
    if volume > 0.0:
        # the buoyancy acts through B: M = (B - c) x F with F = (0, 0, F_z) gives B's x and y;
        # U = rho g V (level - z_B) gives its z
        bx = c[0] - m[1] / f[2] if f[2] != 0.0 else c[0]
        by = c[1] + m[0] / f[2] if f[2] != 0.0 else c[1]
        bz = level - u / (density * g * volume)
        centre = np.array([bx, by, bz])
    else:
        centre = c.copy()
    return Hydrostatics(f, m, u, volume, centre)


def restoring_stiffness(ship, step: float = 1e-6) -> np.ndarray:
    """(6, 6) the water's stiffness on small rigid motions of ``ship`` (a
    :class:`pdfem.motion.ship.Ship`) about its pose now: ``-d(F, M_G) / d(dc, dtheta)``, the
    hydrostatic force (N) and moment about G (N m) against a displacement (m) of G and a rotation
    (rad), body axes, by central differences of :func:`hydrostatics` with ``step`` (m, rad),
    symmetrised (the heave, roll and pitch springs: ``rho g A_wp``, ``rho g V GM``).
    """
    R = ship.R
    out = np.zeros((6, 6))
    for j in range(6):
        loads = []
        for sign in (1.0, -1.0):
            d = np.zeros(6)
            d[j] = sign * step
            c = ship.c + R @ d[:3]
            turned = R @ rotation_matrix(d[3:])
            h = hydrostatics(c + ship.body_points @ turned.T, ship.surface_triangles,
                             ship.level, ship.density, ship.g, c)
            loads.append(np.concatenate([R.T @ h.force, R.T @ h.moment]))
        out[:, j] = -(loads[0] - loads[1]) / (2.0 * step)
    return 0.5 * (out + out.T)
