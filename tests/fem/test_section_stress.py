"""Nominal section stress from resultants (:mod:`pdfem.fem.section_stress`).

References: the section properties of a rectangle, A = b h and I = b h^3 / 12 about its
centroidal axis (any strength-of-materials text); their rotation to principal axes; the
flexure formula sigma = N / A + M c / I of a cantilever's root under a tip load (statics: the
root carries the load's moment F L); the projected area of a cylinder patch, 2 r sin(theta) L.
"""

from __future__ import annotations

import numpy as np
import pytest

from pdfem.fem.section_stress import (nominal_stress, principal_axes, resultants, section_axes,
                                      section_of)


def _grid(u: np.ndarray, v: np.ndarray, place) -> tuple[np.ndarray, np.ndarray]:
    """Points ``place(U, V)`` ((N, 3)) of the grid u x v and its triangles (two per cell)."""
    U, V = np.meshgrid(u, v, indexing="ij")
    pts = place(U.ravel(), V.ravel())
    n = len(v)
    tri = []
    for i in range(len(u) - 1):
        for j in range(n - 1):
            a, b, c, d = i * n + j, (i + 1) * n + j, (i + 1) * n + j + 1, i * n + j + 1
            tri += [[a, b, c], [a, c, d]]
    return pts, np.array(tri)


def _rectangle(b: float, h: float, angle: float, offset=(0.3, 0.2, -0.1)):
    """A b x h rectangle (m) in the plane x = offset[0] (normal +x), its b side turned by
    ``angle`` (rad) from +y toward +z, centred at ``offset``."""
    c, s = np.cos(angle), np.sin(angle)

    def place(u, v):
        return np.column_stack([np.full_like(u, offset[0]), offset[1] + u * c - v * s,
                                offset[2] + u * s + v * c])
    return _grid(np.linspace(-b / 2, b / 2, 7), np.linspace(-h / 2, h / 2, 4), place)


def test_rectangle_area_centroid_and_second_moments():
    """A 0.3 m x 0.05 m rectangle: A = b h, centroid at its centre, I = b h^3/12 and h b^3/12
    about its own axes, whatever its angle in the plane; a triangulation's integrals are exact."""
    b, h = 0.3, 0.05
    axes = section_axes((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    for angle in (0.0, 0.6):
        pts, tri = _rectangle(b, h, angle)
        sec = section_of(pts, tri, axes)
        assert sec.area == pytest.approx(b * h, rel=1e-12)
        np.testing.assert_allclose(sec.centroid, (0.3, 0.2, -0.1), atol=1e-14)
        values, directions = principal_axes(sec)
        np.testing.assert_allclose(values, [b * h**3 / 12, h * b**3 / 12], rtol=1e-12)
        # the weak axis (smallest I) runs along the long side b, at ``angle`` from e1 = +y
        assert abs(directions[0] @ (np.cos(angle), np.sin(angle))) == pytest.approx(1.0)


def test_tip_load_gives_the_flexure_formula_at_the_extreme_fibres():
    """A cantilever of that section along +x (length L = 0.8 m) under a tip force F along the
    section's thin direction: the root carries the moment F L, and the nominal stress is
    +-F L (h/2) / (b h^3/12) at the faces, plus N / A with an axial pull N; a turned section
    gives the same numbers (principal axes)."""
    b, h, L, F, N = 0.3, 0.05, 0.8, 2.0e3, 5.0e4
    axes = section_axes((1.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    for angle in (0.0, 0.6):
        pts, tri = _rectangle(b, h, angle)
        sec = section_of(pts, tri, axes)
        thin = np.array([0.0, -np.sin(angle), np.cos(angle)])      # along h
        # supports' forces on two root nodes that balance F thin at the tip and a pull N e_x:
        # a force and a couple, statically equivalent to any distribution
        tip = sec.centroid + (L, 0.0, 0.0)
        load = F * thin + (N, 0.0, 0.0)
        moment = np.cross(tip - sec.centroid, load)
        arm = np.array([0.1, 0.0, 0.0])                            # normal to the moment
        r1 = -np.cross(moment, arm) / (arm @ arm)                  # arm x r1 = -moment
        positions = np.array([sec.centroid + arm, sec.centroid])
        reactions = np.array([r1, -load - r1])                     # they hold the blade
        force, m = resultants(sec, positions, reactions)
        np.testing.assert_allclose(force, axes @ load, atol=1e-9)
        np.testing.assert_allclose(m, axes @ moment, atol=1e-9)
        sigma = nominal_stress(sec, force, m)
        bending = F * L * (h / 2) / (b * h**3 / 12)
        assert sigma.max() == pytest.approx(N / (b * h) + bending, rel=1e-12)
        assert sigma.min() == pytest.approx(N / (b * h) - bending, rel=1e-12)


def test_cylinder_patch_is_projected_onto_the_plane_normal_to_the_spindle():
    """A patch of the cylinder y^2 + z^2 = r^2 (the hub), angles -t..t about +z and x in
    0..L: its section normal to +z has the projected area 2 r sin(t) L (the radial force of a
    uniform normal stress sigma on it is sigma times that area)."""
    r, t, L = 0.3, 0.44, 0.2

    def place(u, v):
        return np.column_stack([v, r * np.sin(u), r * np.cos(u)])
    pts, tri = _grid(np.linspace(-t, t, 801), np.linspace(0.0, L, 3), place)
    sec = section_of(pts, tri, section_axes((0.0, 0.0, 1.0), (0.0, -1.0, 0.0)))
    assert sec.area == pytest.approx(2 * r * np.sin(t) * L, rel=1e-6)
    assert sec.inertia[0, 0] == pytest.approx(L * (2 * r * np.sin(t))**3 / 12, rel=1e-5)
