"""Cubic particle lattices: counts, positions and volumes.

References: exact counts for boxes whose sides are multiples of dx; the analytic volumes
4/3 pi r^3 (sphere) and pi r^2 L (cylinder), which the particle count times dx^3 must approach;
for a closed triangle mesh the volume it encloses by the divergence theorem.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pdfem.geometry.lattice import fill, lattice_points, particle_volume
from pdfem.geometry.shapes import Box, ClosedSurface, Cylinder, Sphere


def test_box_is_filled_exactly_cell_centred():
    """1 x 0.5 x 0.2 m with dx = 0.1 m: 10*5*2 particles at lo + (i + 1/2) dx, volume 0.1 m^3."""
    dx = 0.1
    x = fill(Box((0.0, 0.0, 0.0), (1.0, 0.5, 0.2)), dx)
    assert x.shape == (100, 3) and x.dtype == np.float64
    np.testing.assert_allclose(x.min(axis=0), [0.05, 0.05, 0.05], atol=1e-15)
    np.testing.assert_allclose(x.max(axis=0), [0.95, 0.45, 0.15], atol=1e-15)
    assert x.shape[0] * particle_volume(dx) == pytest.approx(1.0 * 0.5 * 0.2, rel=1e-12)
    # every particle is the centre of its own dx^3 cell: distinct cells, all in the box
    cells = np.floor(x / dx).astype(int)
    assert np.unique(cells, axis=0).shape[0] == 100
    # x-major / y / z order: z varies fastest, then y, then x
    np.testing.assert_allclose(x[1] - x[0], [0.0, 0.0, dx], atol=1e-15)
    np.testing.assert_allclose(x[2] - x[0], [0.0, dx, 0.0], atol=1e-15)
    np.testing.assert_allclose(x[10] - x[0], [dx, 0.0, 0.0], atol=1e-15)
    order = np.lexsort((x[:, 2], x[:, 1], x[:, 0]))
    assert np.array_equal(order, np.arange(100))


def test_box_anchored_at_its_minimum_corner():
    """Negative, non-aligned corners: the lattice starts at min + dx/2."""
    x = fill(Box((-1.23, 4.5, -0.07), (-0.83, 4.7, 0.13)), 0.05)
    assert x.shape == (8 * 4 * 4, 3)
    np.testing.assert_allclose(x[0], [-1.23 + 0.025, 4.525, -0.045], atol=1e-12)


def test_thin_box_gets_one_layer():
    """A box thinner than dx still gets n_k = 1 layer, centred half a spacing above its minimum."""
    x = fill(Box((0.0, 0.0, 0.0), (0.3, 0.3, 0.04)), 0.1)
    assert x.shape == (9, 3)
    np.testing.assert_allclose(x[:, 2], 0.05)


def test_particle_volume():
    """Each particle owns a cube of side dx."""
    assert particle_volume(0.02) == pytest.approx(8e-6, rel=1e-15)
    with pytest.raises(ValueError):
        particle_volume(0.0)
    with pytest.raises(ValueError):
        fill(Box((0, 0, 0), (1, 1, 1)), -0.1)


@pytest.mark.parametrize("center", [(0.0, 0.0, 0.0), (0.31, -1.7, 2.05)])
def test_sphere_volume_converges(center):
    """Sphere of r = 10 dx: N dx^3 within 2 % of 4/3 pi r^3; all particles inside."""
    dx, r = 0.01, 0.1
    sph = Sphere(center, r)
    x = fill(sph, dx)
    exact = 4.0 / 3.0 * math.pi * r ** 3
    assert x.shape[0] * particle_volume(dx) == pytest.approx(exact, rel=0.02)
    assert np.all(np.linalg.norm(x - center, axis=1) <= r * (1 + 1e-9))
    # a finer lattice is closer (r = 20 dx)
    fine = fill(sph, dx / 2).shape[0] * particle_volume(dx / 2)
    assert abs(fine - exact) < abs(x.shape[0] * particle_volume(dx) - exact) + 1e-3 * exact


@pytest.mark.parametrize("axis", [(0.0, 0.0, 1.0), (1.0, 1.0, 0.5)])
def test_cylinder_volume_converges(axis):
    """Cylinder of r = 10 dx, L = 20 dx: N dx^3 within 2 % of pi r^2 L, axis-aligned or tilted."""
    dx = 0.05
    cyl = Cylinder((0.2, 0.1, -0.3), axis, 10 * dx, 20 * dx)
    x = fill(cyl, dx)
    exact = math.pi * (10 * dx) ** 2 * (20 * dx)
    assert x.shape[0] * particle_volume(dx) == pytest.approx(exact, rel=0.02)
    assert cyl.contains(x).all()


def test_closed_surface_fill_matches_enclosed_volume():
    """A closed octahedron |x| + |y| + |z| <= 1 (volume 4/3, also by the divergence theorem):
    N dx^3 within 1 %, and exactly the particles of the analytic predicate (with dx = 0.05 no
    lattice point lies on its surface)."""
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    t = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4],
                  [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]], dtype=np.int32)
    surf = ClosedSurface(v, t)
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    enclosed = abs(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)
    assert enclosed == pytest.approx(4.0 / 3.0, rel=1e-12)
    dx = 0.05
    x = fill(surf, dx)
    assert x.shape[0] * particle_volume(dx) == pytest.approx(enclosed, rel=0.01)
    grid = lattice_points(*surf.bounds(), dx)
    assert np.array_equal(x, grid[np.abs(grid).sum(axis=1) < 1.0])


def test_lattice_points_counts_round_to_the_nearest_multiple():
    """n_k = max(1, round((hi - lo) / dx)): 0.96 / 0.1 -> 10, 1.04 / 0.1 -> 10, 0.04 / 0.1 -> 1."""
    x = lattice_points(np.zeros(3), np.array([0.96, 1.04, 0.04]), 0.1)
    assert x.shape == (10 * 10 * 1, 3)
