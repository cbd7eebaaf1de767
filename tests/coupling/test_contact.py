"""Surface-element contact (pdfem.coupling.contact): narrow phase, side decision, impulses.

References: brute-force closest points (every vertex, edge and face of a triangle tried in
turn), the analytic closest point on a cube's surface, and the conservation of linear momentum
(the impulse that leaves the ice reaches the structure's nodes).
"""

from __future__ import annotations

import numpy as np
import pytest

from pdfem.coupling.contact import SurfaceContact
from pdfem.coupling.facets import closest_point_on_triangle
from pdfem.motion.rigid import RigidBody


def _segment_closest(p, a, b):
    t = np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
    return a + t * (b - a)


def _brute_closest(p, a, b, c):
    cands = [a, b, c, _segment_closest(p, a, b), _segment_closest(p, b, c),
             _segment_closest(p, c, a)]
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n)
    q = p - np.dot(p - a, n) * n
    m = np.array([a - q, b - q, c - q])
    # inside test by signed sub-areas
    s = [np.dot(np.cross(m[k], m[(k + 1) % 3]), n) for k in range(3)]
    if min(s) >= 0:
        cands.append(q)
    d = [np.linalg.norm(p - x) for x in cands]
    return cands[int(np.argmin(d))]


def test_closest_point_matches_brute_force():
    """Ericson's region-based closest point equals the best of all vertex, edge and face
    candidates, for random triangles (incl. slivers) and points all around them."""
    rng = np.random.default_rng(0)
    for _ in range(3000):
        a, b, c = rng.standard_normal((3, 3))
        if rng.random() < 0.2:
            c = a + (b - a) * rng.random() + 1e-3 * rng.standard_normal(3)  # sliver
        p = rng.standard_normal(3) * 2
        u, v, w, feat = closest_point_on_triangle(p, a, b, c)
        q = u * a + v * b + w * c
        ref = _brute_closest(p, a, b, c)
        assert np.linalg.norm(q - ref) <= 1e-9 * (1 + np.linalg.norm(ref))
        assert min(u, v, w) >= -1e-12 and abs(u + v + w - 1) < 1e-12


def cube(half=0.5, velocity=(0.0, 0.0, 0.0)):
    corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float) * half
    quads = [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]
    tris = [[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads]
    return RigidBody(corners, np.array(tris), velocity=velocity, name="cube")


def _cube_surface_closest(p, half):
    """Analytic closest point on the surface of the cube [-half, half]^3 of a point inside it:
    move the coordinate nearest to a face onto that face."""
    q = p.copy()
    k = int(np.argmax(np.abs(p)))
    q[k] = np.sign(p[k]) * half
    return q


@pytest.mark.parametrize("where", ["faces", "edges", "vertices"])
def test_particles_inside_a_cube_are_pushed_out_once_to_the_nearest_face(where):
    """Particles that crossed into a closed cube in this step, near its faces, edges (edge-on)
    and vertices, end on the surface at the analytic closest point (the correct side), a second
    pass finds nothing inside, and particles just outside are left alone. The impulse taken from the ice equals
    the impulse the cube's nodes receive (momentum conservation, to round-off)."""
    half = 0.5
    rng = np.random.default_rng({"faces": 1, "edges": 2, "vertices": 3}[where])
    n = 400
    depth = 0.02
    p = rng.uniform(-half + depth, half - depth, (n, 3))
    k = {"faces": 1, "edges": 2, "vertices": 3}[where]
    for i in range(n):
        axes = rng.permutation(3)[:k]
        for a in axes:
            p[i, a] = rng.choice([-1, 1]) * (half - rng.uniform(1e-9, depth))
    outside = p.copy()
    outside[:, 0] = np.where(p[:, 0] > 0, 1, -1) * (half + rng.uniform(1e-9, depth, n))
    body = cube(half)
    con = SurfaceContact(body, search_radius=0.05)
    ref = np.array([_cube_surface_closest(q, half) for q in p])
    y_old = 2 * ref - p   # outside at the step's start: the particles crossed in this step
    y = np.vstack([p, outside])
    y_old = np.vstack([y_old, outside])
    v = (y - y_old) / 1e-3              # the velocity the particles moved with
    v0 = v.copy()
    mass = np.full(len(y), 2.0)
    step = con.resolve(y, y_old, v, mass, 1e-3)
    assert step.contacts == n
    np.testing.assert_allclose(y[:n], ref, atol=1e-12)
    np.testing.assert_array_equal(y[n:], outside)
    assert not con.inside(y).any()
    assert con.resolve(y, y.copy(), v.copy(), mass, 1e-3).contacts == 0
    # momentum: ice gained sum m (v - v0), the cube's nodes got the opposite impulse
    ice = (mass[:, None] * (v - v0)).sum(axis=0)
    np.testing.assert_allclose(ice + con.take_impulse().sum(axis=0), 0.0, atol=1e-12)


def test_open_surface_rim_and_moving_surface():
    """A square plate (open surface, normal +z) moving up at 1 m/s: a particle that crossed it
    gets the plate's velocity (Eq. 5 with y_old on the plate's old position), one beside the
    rim is left alone, and the impulse is m (v - v_bar) on the facet's nodes."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    plate = RigidBody(pts, np.array([[0, 1, 2], [0, 2, 3]]), velocity=(0, 0, 1.0), name="plate")
    dt = 1e-3
    con = SurfaceContact(plate, search_radius=0.01)
    start = plate.surface_points().copy()
    plate.step(dt)                                       # plate now at z = 1e-3
    con.set_surface(plate.surface_points(), plate.surface_velocities(), start=start)
    y_old = np.array([[0.3, 0.6, 0.0], [1.2, 0.5, 0.0]])
    v = np.array([[0.0, 0.0, -0.5], [0.0, 0.0, -0.5]])
    y = y_old + dt * v
    mass = np.array([1.0, 1.0])
    s = con.resolve(y, y_old, v, mass, dt)
    assert s.contacts == 1
    np.testing.assert_allclose(y[0], [0.3, 0.6, 1e-3], atol=1e-15)
    np.testing.assert_allclose(v[0], [0, 0, 1.0], atol=1e-12)      # the plate's velocity
    np.testing.assert_allclose(s.impulse, [0, 0, -1.5], atol=1e-12)
    np.testing.assert_allclose(v[1], [0, 0, -0.5])                  # beside the rim: untouched
    np.testing.assert_allclose(con.take_impulse().sum(axis=0), [0, 0, -1.5], atol=1e-12)


def test_coulomb_friction_limits_the_tangential_change():
    """Sliding on a fixed plate with friction mu: the tangential velocity drops by mu times the
    normal velocity change (Coulomb), or stops if that is more."""
    pts = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float)
    plate = RigidBody(pts, np.array([[0, 1, 2], [0, 2, 3]]), name="plate")
    dt = 1e-3
    for mu, vx_after in ((0.1, 2.0 - 0.1 * 1.0), (5.0, 0.0)):
        con = SurfaceContact(plate, search_radius=0.01, friction=mu)
        y_old = np.array([[0.0, 0.0, 0.0]])
        v = np.array([[2.0, 0.0, -1.0]])
        y = y_old + dt * v
        con.resolve(y, y_old, v, np.array([1.0]), dt)
        np.testing.assert_allclose(v[0], [vx_after, 0, 0], atol=1e-12)
        assert abs(y[0, 2]) < 1e-15     # back on the plate, to round-off
