"""Blade-section laws of the parametric propeller (``models/propeller.py``): chord from the
expanded area ratio, thickness, pitch, skew and rake, the helicoidal section points and the
analytic section area and blade volume. SI units (m, rad).

Geometry: the shaft axis is x; a point at radius r and angle psi around the shaft (measured
from +z toward +y) is (x, r sin psi, r cos psi). Blade k's reference line is at
psi_k = 2 pi (k - 1) / Z.

* Chord: the elliptic-type shape of ``models/propeller_blade.py``,
  ``c(r) = c_max sqrt(1 - s^2 (1 - q^2))``, ``s = (r - r_m) / (R - r_m)``, q the tip-to-largest
  chord ratio, r_m the radius of the largest chord; c_max follows from the expanded area ratio
  ``EAR = Z int_{r_h}^{R} c(r) dr / (pi R^2)``.
* Thickness: thickness/chord ratio linear in r from ``root_thickness_ratio`` at the hub to
  ``tip_thickness_ratio`` at the tip, t(r) = tau(r) c(r); symmetric NACA 00xx sections with a
  closed trailing edge, opened linearly from the leading edge to a flat trailing-edge face
  ``trailing_edge_ratio`` x t thick (half thickness + te t b / 2; a blunt edge keeps the
  tetrahedra at the edge from becoming slivers, which would set the explicit time step); area
  ``(NACA_AREA_FACTOR + te / 2) c t`` (NACA_AREA_FACTOR = 0.68088).
* Pitch: constant, pitch angle phi(r) = atan(P / (2 pi r)); leading edge at larger x, back
  (suction side) facing +x, face (pressure side) -x. Turning positively about +x the leading
  edge is ahead.
* Skew: the mid-chord point at psi_k + skew_angle (r - r_h) / (R - r_h) (skew-back > 0).
* Rake: the mid-chord point moved along x by -(r - r_h) tan(rake_angle) (aft rake > 0, 0 at
  the hub so that the root face lies on the hub cylinder).

Each section is wrapped onto its cylinder r = const (helicoidal), which is length-preserving,
so the section area on the cylinder is the NACA area and the blade volume is exactly
``int_{r_h}^{R} A(r) dr``.
"""

from __future__ import annotations

import math

import numpy as np

from pdfem.models.propeller_blade import NACA_AREA_FACTOR, _CLOSED_TE

__all__ = ["NACA_AREA_FACTOR", "chord_shape", "max_chord", "chord", "thickness_ratio", "thickness", "section_area",
           "blade_volume", "expanded_area_ratio", "profile", "section_points", "chordwise"]

_GAUSS = np.polynomial.legendre.leggauss(64)


def _integrate(f, a: float, b: float) -> float:
    """64-point Gauss-Legendre quadrature of a smooth f on [a, b]."""
    x, w = _GAUSS
    r = 0.5 * (b - a) * x + 0.5 * (b + a)
    return float(0.5 * (b - a) * np.sum(w * f(r)))


def chord_shape(r: np.ndarray, p: dict) -> np.ndarray:
    """c(r) / c_max (-) of the elliptic-type chord law at radii r (m)."""
    R, rm, q = p["diameter"] / 2, p["max_chord_radius"], p["tip_chord_ratio"]
    s = (np.asarray(r, float) - rm) / (R - rm)
    return np.sqrt(np.maximum(1.0 - s * s * (1.0 - q * q), 0.0))


def max_chord(p: dict) -> float:
    """The largest chord c_max (m) that gives the expanded area ratio ``p['ear']``."""
    R = p["diameter"] / 2
    return p["ear"] * math.pi * R * R / (p["blades"] * _integrate(lambda r: chord_shape(r, p), p["hub_diameter"] / 2, R))


def chord(r, p: dict) -> np.ndarray:
    """Chord c(r) (m) at radii r (m)."""
    return max_chord(p) * chord_shape(r, p)


def thickness_ratio(r, p: dict) -> np.ndarray:
    """Thickness/chord ratio tau(r) (-), linear from the hub to the tip."""
    rh, R = p["hub_diameter"] / 2, p["diameter"] / 2
    f = (np.asarray(r, float) - rh) / (R - rh)
    return p["root_thickness_ratio"] + f * (p["tip_thickness_ratio"] - p["root_thickness_ratio"])


def thickness(r, p: dict) -> np.ndarray:
    """Maximum section thickness t(r) = tau(r) c(r) (m)."""
    return thickness_ratio(r, p) * chord(r, p)


def section_area(r, p: dict) -> np.ndarray:
    """Analytic section area A(r) = (NACA_AREA_FACTOR + te / 2) c t (m^2), te the trailing-edge
    thickness over the NACA maximum thickness."""
    return (NACA_AREA_FACTOR + 0.5 * p["trailing_edge_ratio"]) * chord(r, p) * thickness(r, p)


def blade_volume(p: dict) -> float:
    """Volume of one blade, int_{r_h}^{R} A(r) dr (m^3)."""
    return _integrate(lambda r: section_area(r, p), p["hub_diameter"] / 2, p["diameter"] / 2)


def expanded_area_ratio(p: dict) -> float:
    """Z int c dr / (pi R^2) (-) of the chord law as built (checks :func:`max_chord`)."""
    R = p["diameter"] / 2
    return p["blades"] * _integrate(lambda r: chord(r, p), p["hub_diameter"] / 2, R) / (math.pi * R * R)


def profile(ratio: float, edge: float, te: float, n: int = 8) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """Open NACA 00xx loop of chord 1 with break points at the chordwise fractions ``edge``
    and ``1 - edge`` from the leading edge (b = 0) on both sides.

    The half thickness is the NACA 00xx one (closed trailing edge) plus ``te ratio b / 2``, so
    that the trailing edge is a flat face ``te`` x the NACA maximum thickness thick.
    Returns xi (chordwise, 0 at LE, 1 at TE), eta (thickness direction, > 0 on the back) of the
    loop TE back -> back -> LE -> face -> TE face (the closing segment is the TE face), and the
    loop indices of the seven break points: TE back, back 1-edge, back edge, LE, face edge,
    face 1-edge, TE face.
    """
    th = np.linspace(0.0, 0.5 * np.pi, n + 1)
    nose = edge * (1.0 - np.cos(th))                                          # clustered at the LE
    mid = edge + (1.0 - 2.0 * edge) * 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, 2 * n + 1)))
    tail = np.linspace(1.0 - edge, 1.0, n + 1)
    b = np.concatenate([nose, mid[1:], tail[1:]])                             # 0 .. 1
    a0, a1, a2, a3, a4 = _CLOSED_TE
    y = 5 * ratio * (a0 * np.sqrt(b) + a1 * b + a2 * b**2 + a3 * b**3 + a4 * b**4)
    y[-1] = 0.0
    y += 0.5 * te * ratio * b
    m = len(b) - 1                                                            # index of the TE in b
    xi = np.concatenate([b[::-1], b[1:]])
    eta = np.concatenate([y[::-1], -y[1:]])
    return xi, eta, [0, n, m - n, m, m + n, 2 * m - n, 2 * m]


def section_points(r: float, r_law: float, p: dict, psi0: float = 0.0) -> tuple[np.ndarray, list[int]]:
    """Points (n, 3) of the helicoidal section on the cylinder of radius r (laws at r_law) of the
    blade whose reference line is at psi0, and the loop indices of its break points."""
    c = float(chord(r_law, p))
    xi, eta, breaks = profile(float(thickness_ratio(r_law, p)), p["edge_fraction"], p["trailing_edge_ratio"])
    xi = (xi - 0.5) * c
    eta = eta * c
    phi = math.atan(p["pitch_ratio"] * p["diameter"] / (2 * math.pi * r))
    s = xi * math.cos(phi) + eta * math.sin(phi)
    rh, R = p["hub_diameter"] / 2, p["diameter"] / 2
    f = (r_law - rh) / (R - rh)
    x = -xi * math.sin(phi) + eta * math.cos(phi) - (r_law - rh) * math.tan(p["rake_angle"])
    psi = s / r + psi0 + p["skew_angle"] * f
    return np.column_stack([x, r * np.sin(psi), r * np.cos(psi)]), breaks


def chordwise(xyz: np.ndarray, p: dict, psi0: float) -> tuple[np.ndarray, np.ndarray]:
    """Chordwise fraction b (0 at the LE, 1 at the TE) and thickness coordinate eta (m, > 0 on
    the back) of points xyz (n, 3) of the blade whose reference line is at psi0."""
    r = np.hypot(xyz[:, 1], xyz[:, 2])
    rh, R = p["hub_diameter"] / 2, p["diameter"] / 2
    f = (r - rh) / (R - rh)
    psi = np.arctan2(xyz[:, 1], xyz[:, 2]) - psi0 - p["skew_angle"] * f
    psi = (psi + np.pi) % (2 * np.pi) - np.pi
    s = r * psi
    x = xyz[:, 0] + (r - rh) * math.tan(p["rake_angle"])
    phi = np.arctan(p["pitch_ratio"] * p["diameter"] / (2 * np.pi * r))
    xi = s * np.cos(phi) - x * np.sin(phi)
    eta = s * np.sin(phi) + x * np.cos(phi)
    return xi / chord(r, p) + 0.5, eta
