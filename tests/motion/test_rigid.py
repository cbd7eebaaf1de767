"""Rigid bodies with prescribed motion: exact kinematics, outward normals, contact-load reports.

Surfaces are gmsh surface meshes (a closed cylinder and a sphere, 'contact' group only) written
into tmp_path, and the top face of a block (the ``gmsh_box`` fixture of conftest.py) read both
as a rigid body and as an elastic structure. References: rigid-body kinematics (circular motion,
v = v0 + w x r), Rodrigues' formula vs scipy's rotation, outward normals of convex closed
surfaces, the divergence theorem for the enclosed volume, and the definitions of resultant force
and moment.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pdfem.motion.rigid import RigidBody, read_surface, rotation_matrix
from pdfem.fem.elasticity import ElasticMaterial
from pdfem.fem.mesh import load_mesh
from pdfem.fem.structure import ElasticStructure
from pdfem.fem.surface import ContactSurface, orient_outward
from pdfem.meshing import gmsh_session

R_CYL, LEN = 0.2, 0.5
R_SPH = 0.3
CENTRE = np.array([1.0, -0.5, 0.25])


def write_surface(path, shape, size):
    """Surface-only mesh of a closed cylinder (axis z, base at CENTRE) or a sphere at CENTRE,
    all faces in the group 'contact'."""
    with gmsh_session(shape) as gmsh:
        if shape == "cylinder":
            gmsh.model.occ.addCylinder(*CENTRE, 0.0, 0.0, LEN, R_CYL)
        else:
            gmsh.model.occ.addSphere(*CENTRE, R_SPH)
        gmsh.model.occ.synchronize()
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.model.addPhysicalGroup(2, [s for _, s in gmsh.model.getEntities(2)], name="contact")
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
    return path


@pytest.fixture(scope="module")
def cylinder_file(tmp_path_factory):
    return write_surface(tmp_path_factory.mktemp("rigid") / "cylinder.msh", "cylinder", 0.05)


@pytest.fixture(scope="module")
def sphere_file(tmp_path_factory):
    return write_surface(tmp_path_factory.mktemp("rigid") / "sphere.msh", "sphere", 0.06)


def enclosed_volume(points, triangles):
    x = points[triangles]
    return np.einsum("ij,ij->i", x[:, 0], np.cross(x[:, 1], x[:, 2])).sum() / 6.0


def test_rotating_cylinder_points_move_on_circles(cylinder_file):
    """A cylinder spinning about its axis at w = 40 rad/s while translating at v: after 5000
    steps (about 13 revolutions) every node is at c0 + v t + R(w t)(X - c0) with the angle w t
    exactly, at its original distance from the moving axis (reference: rigid-body kinematics,
    circular motion)."""
    v = np.array([0.3, -0.1, 0.05])
    w = 40.0
    body = RigidBody.from_msh(cylinder_file, "contact", velocity=v, angular_velocity=(0, 0, w),
                              centre=CENTRE)
    x0 = body.surface_points()
    dt = 4.0e-4
    steps = 5000
    for _ in range(steps):
        body.step(dt)
    t = steps * dt
    assert body.time == pytest.approx(t, rel=1e-12)
    c = CENTRE + v * t
    rel0 = x0 - CENTRE
    ang = w * t
    expected = np.column_stack([
        rel0[:, 0] * math.cos(ang) - rel0[:, 1] * math.sin(ang),
        rel0[:, 0] * math.sin(ang) + rel0[:, 1] * math.cos(ang),
        rel0[:, 2]]) + c
    x = body.surface_points()
    assert np.abs(x - expected).max() < 1e-12
    r0 = np.hypot(rel0[:, 0], rel0[:, 1])
    r = np.hypot(x[:, 0] - c[0], x[:, 1] - c[1])
    assert np.abs(r - r0).max() < 1e-12
    # velocities: v + w x (x - c); on the mantle |v - v0| = w R
    vel = body.surface_velocities()
    assert vel == pytest.approx(v + np.cross([0, 0, w], x - c), abs=1e-12)
    mantle = np.abs(r0 - R_CYL) < 1e-9
    assert mantle.sum() > 20
    assert np.linalg.norm(vel[mantle] - v, axis=1) == pytest.approx(w * R_CYL, rel=1e-9)


def test_velocities_are_the_time_derivative_of_positions(cylinder_file):
    """Surface velocities equal the central finite difference of the exact positions for a
    general rotation axis (reference: kinematics, d/dt x(t))."""
    kw = dict(velocity=(0.2, 0.0, -0.4), angular_velocity=(1.0, -2.0, 0.5), centre=CENTRE)
    body = RigidBody.from_msh(cylinder_file, **kw)
    h = 1e-6
    body.step(0.37 - h)
    xm = body.surface_points()
    body.step(h)
    v = body.surface_velocities()
    body.step(h)
    xp = body.surface_points()
    assert v == pytest.approx((xp - xm) / (2 * h), abs=1e-6)


def test_rodrigues_matches_scipy_rotation():
    """rotation_matrix(r) equals scipy's Rotation.from_rotvec(r) (independent reference) and is
    orthogonal with determinant 1."""
    for r in ([0.0, 0.0, 0.0], [0.1, -0.3, 2.0], [10.0, 3.0, -7.0]):
        Rm = rotation_matrix(r)
        assert Rm == pytest.approx(Rotation.from_rotvec(r).as_matrix(), abs=1e-14)
        assert Rm @ Rm.T == pytest.approx(np.eye(3), abs=1e-14)
        assert np.linalg.det(Rm) == pytest.approx(1.0)


def test_sphere_normals_point_outward_even_from_scrambled_input(sphere_file):
    """Normals of the closed sphere surface point outward: n . (triangle centroid - centre) > 0
    for every triangle, both as read and after flipping a random half of the triangles; the
    enclosed volume is 4/3 pi R^3 within 2 % (reference: divergence theorem)."""
    pts, tri = read_surface(sphere_file, "contact")
    rng = np.random.default_rng(3)
    scrambled = tri.copy()
    flip = rng.random(len(tri)) < 0.5
    scrambled[flip] = scrambled[flip][:, ::-1]
    for t in (tri, scrambled):
        body = RigidBody(pts, t, centre=CENTRE)
        n = body.facet_normals()
        x = body.surface_points()[body.surface_triangles]
        assert np.all(np.einsum("ij,ij->i", n, x.mean(axis=1) - CENTRE) > 0)
        assert np.linalg.norm(n, axis=1) == pytest.approx(1.0)
    vol = enclosed_volume(pts, body.surface_triangles)
    assert vol == pytest.approx(4 / 3 * math.pi * R_SPH**3, rel=0.02)
    # normals follow the rotation: after a quarter turn about z they are still outward
    body = RigidBody(pts, scrambled, angular_velocity=(0, 0, 1.0), centre=CENTRE)
    body.step(math.pi / 2)
    n = body.facet_normals()
    x = body.surface_points()[body.surface_triangles]
    assert np.all(np.einsum("ij,ij->i", n, x.mean(axis=1) - CENTRE) > 0)


def test_orient_outward_refuses_non_manifold_surfaces():
    """Three triangles on one edge are refused (not a manifold surface)."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1.0]])
    with pytest.raises(ValueError, match="more than two triangles"):
        orient_outward(pts, np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]]))


def test_contact_force_and_moment_are_reported_not_applied(cylinder_file):
    """Accumulated surface forces add up; the total force is their sum and the moment about the
    centre is sum (x - c) x f (reference: resultant definitions); they do not change the
    prescribed motion; clear resets; the stable step is infinite."""
    kw = dict(velocity=(1.0, 0, 0), angular_velocity=(0, 0, 3.0), centre=CENTRE)
    a = RigidBody.from_msh(cylinder_file, **kw)
    b = RigidBody.from_msh(cylinder_file, **kw)
    assert isinstance(a, ContactSurface)
    rng = np.random.default_rng(0)
    f1 = rng.standard_normal((a.n_surface_nodes, 3))
    f2 = rng.standard_normal((a.n_surface_nodes, 3))
    a.add_surface_forces(f1)
    a.add_surface_forces(f2)
    for _ in range(10):
        a.step(1e-3)
        b.step(1e-3)
    assert np.array_equal(a.surface_points(), b.surface_points())
    assert a.total_surface_force() == pytest.approx((f1 + f2).sum(axis=0), abs=1e-12)
    c = CENTRE + np.array([1.0, 0, 0]) * a.time
    expected = np.cross(a.surface_points() - c, f1 + f2).sum(axis=0)
    assert a.total_surface_moment() == pytest.approx(expected, abs=1e-12)
    origin = np.cross(a.surface_points(), f1 + f2).sum(axis=0)
    assert a.total_surface_moment(about=(0, 0, 0)) == pytest.approx(origin, abs=1e-12)
    a.clear_surface_forces()
    assert np.all(a.total_surface_force() == 0.0)
    assert a.stable_time_step() == math.inf
    with pytest.raises(ValueError, match="shape"):
        a.add_surface_forces(np.zeros((3, 3)))


def test_missing_surface_group_lists_groups(sphere_file):
    """A missing group raises ValueError listing the file's groups."""
    with pytest.raises(ValueError, match="group 'hull' not in .*; the file has groups: contact"):
        RigidBody.from_msh(sphere_file, "hull")


def test_rigid_and_elastic_bodies_expose_the_same_surface(tmp_path, gmsh_box):
    """A rigid body and an elastic structure read from the same file's 'contact' group (the top
    face z = W of a tetrahedral block) expose the same ContactSurface: the same nodes, the same
    triangles with the same outward normals (+z), zero velocities at rest, the same total force
    and moment of the same nodal forces, and a step that leaves an unloaded body at rest
    (references: the box geometry and the resultant definitions sum f, sum (x - a) x f)."""
    LX, LY, W = 0.3, 0.2, 0.1
    path = gmsh_box(tmp_path / "block.msh", (LX, LY, W), volume_groups=["block"],
                    face_groups={"contact": ["z1"], "fixed": ["x0"]}, size=0.05)
    steel = ElasticMaterial(density=7850.0, youngs_modulus=210e9, poisson_ratio=0.3)
    # first-order elements: the same surface nodes as the rigid body's (quadratic ones add
    # the midside nodes)
    elastic = ElasticStructure(load_mesh(path), steel, fixed_groups=["fixed"], contact_group="contact",
                               element_order=1)
    rigid = RigidBody.from_msh(path, "contact")
    bodies = (rigid, elastic)
    assert all(isinstance(b, ContactSurface) for b in bodies)
    # the same nodes in possibly different order: match them by position
    order = [np.lexsort(b.surface_points().T) for b in bodies]
    x = [b.surface_points()[o] for b, o in zip(bodies, order)]
    assert len(x[0]) == len(x[1]) == rigid.n_surface_nodes == elastic.n_surface_nodes
    assert x[0] == pytest.approx(x[1], abs=1e-15)
    assert np.all(x[0][:, 2] == pytest.approx(W))
    # the same triangles (as sets of positions) with outward normals +z, covering LX LY
    for b in bodies:
        tri = b.surface_points()[b.surface_triangles]
        assert b.surface_triangles.shape[1] == 3
        area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
        assert area.sum() == pytest.approx(LX * LY, rel=1e-12)
        assert b.facet_normals() == pytest.approx(np.tile([0.0, 0.0, 1.0], (len(tri), 1)), abs=1e-12)
        assert np.all(b.surface_velocities() == 0.0)
    centroids = [b.surface_points()[b.surface_triangles].mean(axis=1) for b in bodies]
    centroids = [c[np.lexsort(np.round(c, 12).T)] for c in centroids]
    assert centroids[0] == pytest.approx(centroids[1], abs=1e-15)
    # the same forces (given per node, in each body's own node order) give the same resultants
    f = np.random.default_rng(5).standard_normal((len(x[0]), 3))
    about = np.array([0.1, -0.2, 0.3])
    for b, o in zip(bodies, order):
        fb = np.empty_like(f)
        fb[o] = f
        b.add_surface_forces(fb)
        assert b.total_surface_force() == pytest.approx(f.sum(axis=0), abs=1e-12)
        assert b.total_surface_moment(about) == pytest.approx(np.cross(x[0] - about, f).sum(axis=0), abs=1e-12)
        b.clear_surface_forces()
        assert np.all(b.total_surface_force() == 0.0)
        dt = min(b.stable_time_step(), 1e-6)
        assert dt > 0
        b.step(dt)
        assert np.all(b.surface_velocities() == 0.0)
    assert rigid.stable_time_step() == math.inf and np.isfinite(elastic.stable_time_step())
