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

import numpy as np

from pdfem.geometry.vectors import cross


@dataclass
class Hydrostatics:
    """Result of :func:`hydrostatics` (SI)."""

    force: np.ndarray        # (3,) N, on the hull
    moment: np.ndarray       # (3,) N m, about the centre given
    potential: float         # J, rho g int_V (level - z) dV
    volume: float            # m^3, submerged volume
    centre_of_buoyancy: np.ndarray  # (3,) m (the centre given if nothing is submerged)


def _wet_triangles(x: np.ndarray, tri: np.ndarray, level: float) -> tuple[np.ndarray, np.ndarray]:
    """Corners (K, 3, 3) (m) and depths (K, 3) (m, >= 0) of the submerged parts of the
    triangles, with the triangles' orientation kept."""
    p = x[tri]                                     # (T, 3, 3)
    d = level - p[:, :, 2]                         # depth of each corner
    wet = d > 0.0
    n_wet = wet.sum(axis=1)
    parts = [p[n_wet == 3]]
    depths = [d[n_wet == 3]]
    for count in (1, 2):
        sel = n_wet == count
        if not sel.any():
            continue
        pp, dd, ww = p[sel], d[sel], wet[sel]
        # rotate each triangle cyclically so that the odd corner (the wet one if count == 1, the
        # dry one if count == 2) comes first; a cyclic shift keeps the orientation
        odd = ww if count == 1 else ~ww
        first = np.argmax(odd, axis=1)
        order = (first[:, None] + np.arange(3)[None, :]) % 3
        pp = np.take_along_axis(pp, order[:, :, None], axis=1)
        dd = np.take_along_axis(dd, order, axis=1)
        a, b, c = pp[:, 0], pp[:, 1], pp[:, 2]
        da, db, dc = dd[:, 0:1], dd[:, 1:2], dd[:, 2:3]
        ab = a + (da / (da - db)) * (b - a)        # the waterline crossings (depth 0)
        ac = a + (da / (da - dc)) * (c - a)
        zero = np.zeros_like(da)
        if count == 1:
            parts.append(np.stack([a, ab, ac], axis=1))
            depths.append(np.hstack([da, zero, zero]))
        else:
            parts.append(np.stack([ab, b, c], axis=1))
            depths.append(np.hstack([zero, db, dc]))
            parts.append(np.stack([ab, c, ac], axis=1))
            depths.append(np.hstack([zero, dc, zero]))
    return np.concatenate(parts), np.concatenate(depths)


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
