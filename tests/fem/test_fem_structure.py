"""The elastic structure's surface interface (what the contact code sees) and its loads.

A small steel block from gmsh (tetrahedra, or hexahedra by transfinite meshing; the
``gmsh_box`` fixture of conftest.py) with a 'contact' group on its top face z = W. References:
outward normals of a box, the consistent nodal load of a uniform traction on linear triangles
(t A / 3 per node), Newton's second law for a free body (momentum = F t, and centre-of-mass
motion F t^2 / (2 m), which leapfrog integrates exactly), resultant moment definition, rotation
of normals with the body.
"""

from __future__ import annotations

import numpy as np
import pytest

from pdfem.fem.elasticity import ElasticMaterial, surface_load
from pdfem.fem.mesh import load_mesh
from pdfem.motion.rigid import rotation_matrix
from pdfem.fem.structure import ElasticStructure
from pdfem.fem.surface import ContactSurface

LX, LY, W = 0.4, 0.2, 0.1
STEEL = ElasticMaterial(density=7850.0, youngs_modulus=210e9, poisson_ratio=0.3)


def write_block(gmsh_box, path, hexa):
    """Block [0,LX]x[0,LY]x[0,W]; groups block (3), contact (z = W), fixed (x = 0); hexahedra
    (3 per edge) or tetrahedra of size 0.05 m."""
    return gmsh_box(path, (LX, LY, W), volume_groups=["block"], face_groups={"contact": ["z1"], "fixed": ["x0"]},
                    divisions=(3, 3, 3) if hexa else None, size=0.05)


@pytest.fixture(scope="module", params=["tet", "hex"])
def mesh(request, tmp_path_factory, gmsh_box):
    path = tmp_path_factory.mktemp("block") / f"block_{request.param}.msh"
    return load_mesh(write_block(gmsh_box, path, request.param == "hex"))


def test_surface_geometry_and_outward_normals(mesh):
    """Surface nodes are the contact face's nodes at their reference positions; triangles cover
    the face area LX LY (quads split in two; quadratic faces: 6-node triangles into 4, 8-node
    quads into 6); normals are +z (outward); the structure satisfies the ContactSurface
    protocol."""
    s = ElasticStructure(mesh, STEEL, fixed_groups=["fixed"], contact_group="contact")
    assert isinstance(s, ContactSurface)
    x = s.surface_points()
    assert np.array_equal(np.sort(s.surface_nodes), s.group_nodes("contact"))
    assert np.all(x[:, 2] == pytest.approx(W))
    faces = mesh.group_facets("contact")
    assert len(s.surface_triangles) == len(faces) * (4 if mesh.kind == "tet" else 6)
    tri = x[s.surface_triangles]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    assert area.sum() == pytest.approx(LX * LY, rel=1e-12)
    assert s.facet_normals() == pytest.approx(np.tile([0.0, 0.0, 1.0], (len(tri), 1)), abs=1e-12)
    assert np.all(s.surface_velocities() == 0.0)


def test_normals_and_points_follow_the_current_configuration(mesh):
    """Displaced by a rigid rotation of 90 degrees about x (as a displacement field), surface
    points are R X and the top-face normals are R e_z = -e_y (reference: rotation of a rigid
    body)."""
    s = ElasticStructure(mesh, STEEL, contact_group="contact")
    R = rotation_matrix([np.pi / 2, 0.0, 0.0])
    X = s.points
    s.set_state(displacement=X @ R.T - X)
    assert s.surface_points() == pytest.approx(X[s.surface_nodes] @ R.T, abs=1e-14)
    minus_y = np.tile([0.0, -1.0, 0.0], (len(s.surface_triangles), 1))
    assert s.facet_normals() == pytest.approx(minus_y, abs=1e-12)


def test_contact_forces_match_consistent_traction_load(mesh):
    """Nodal contact forces t A/3 per triangle node equal the consistent load of a uniform
    traction on linear triangles (tetrahedral mesh, to round-off); on any mesh their total is
    t LX LY and they enter the next step's force vector (reference: consistent load vector).
    First-order elements (element_order = 1): the t A/3 rule is the linear triangle's load."""
    s = ElasticStructure(mesh, STEEL, fixed_groups=["fixed"], contact_group="contact",
                         element_order=1)
    t = np.array([1.0e5, -2.0e5, -3.0e6])
    x = s.surface_points()
    tri = s.surface_triangles
    area = 0.5 * np.linalg.norm(np.cross(x[tri[:, 1]] - x[tri[:, 0]], x[tri[:, 2]] - x[tri[:, 0]]),
                                axis=1)
    f = np.zeros((s.n_surface_nodes, 3))
    for k in range(3):
        np.add.at(f, tri[:, k], area[:, None] * t / 3.0)
    s.add_surface_forces(0.5 * f)
    s.add_surface_forces(0.5 * f)
    assert s.total_surface_force() == pytest.approx(t * LX * LY, rel=1e-12)
    fdofs = s.external_force_dofs()
    assert s.dofmap.to_nodal(fdofs).sum(axis=0) == pytest.approx(t * LX * LY, rel=1e-12)
    if mesh.kind == "tet":
        ref = surface_load(mesh, "contact", traction=t)
        assert np.abs(fdofs - ref).max() <= 1e-9 * np.abs(ref).max()
    about = np.array([0.1, 0.2, -0.3])
    moment = np.cross(x - about, f).sum(axis=0)
    assert s.total_surface_moment(about) == pytest.approx(moment, rel=1e-12)
    s.clear_surface_forces()
    assert np.all(s.external_force_dofs() == 0.0)


def test_free_body_obeys_newtons_second_law(mesh):
    """An unsupported block under a constant contact force F (held over the steps): total
    momentum is F t and the mass-weighted mean displacement F t^2 / (2 m) to round-off
    (reference: Newton's second law; leapfrog is exact for uniform acceleration of the centre of
    mass); the support-free reaction is zero."""
    s = ElasticStructure(mesh, STEEL, contact_group="contact")
    F = np.array([3.0e4, -1.0e4, -5.0e4])
    f = np.zeros((s.n_surface_nodes, 3))
    f[0] = F
    s.add_surface_forces(f)
    s.set_state()
    dt = s.stable_time_step()
    n = 300
    for _ in range(n):
        s.step(dt)
    t = n * dt
    m = s.dofmap.to_nodal(s.mass)
    mass_total = m[:, 0].sum()
    assert mass_total == pytest.approx(STEEL.density * LX * LY * W, rel=1e-12)
    assert (m * s.velocity()).sum(axis=0) == pytest.approx(F * t, rel=1e-9)
    com = (m * s.displacement()).sum(axis=0) / mass_total
    assert com == pytest.approx(F * t**2 / (2 * mass_total), rel=1e-9)
    assert s.reaction("contact") == pytest.approx(np.zeros(3), abs=1e-9 * np.abs(F).max())
    assert s.kinetic_energy() > 0 and s.strain_energy() > 0
    assert np.all(np.isfinite(s.nodal_von_mises())) and s.von_mises().shape == (mesh.n_elements,)


def test_missing_groups_are_reported(mesh):
    """Unknown fixed or contact group names raise ValueError naming the groups of the file."""
    with pytest.raises(ValueError, match="group 'clamp' not in .*the file has groups: block, "
                                         "contact, fixed"):
        ElasticStructure(mesh, STEEL, fixed_groups=["clamp"])
    with pytest.raises(ValueError, match="group 'ice_side' not in"):
        ElasticStructure(mesh, STEEL, contact_group="ice_side")
