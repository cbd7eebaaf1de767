"""FE mesh loading and assembly: groups from gmsh files, orientation checks, K and lumped M.

Meshes are generated with the gmsh Python API into tmp_path (a small slender box, the
``gmsh_box`` fixture of conftest.py); tiny hand-written MSH 2.2 files (meshio) cover the error
paths. References: exact geometry (volumes,
areas, outward normals of a box), rigid-body invariance of linear elasticity, the constant-strain
patch test, Newton's third law for surface loads.
"""

from __future__ import annotations

import meshio
import numpy as np
import pytest
from skfem.io.meshio import HEX_MAPPING

from pdfem.fem.elasticity import (DofMap, ElasticMaterial, element_volumes, lumped_mass,
                                  stiffness_matrix, surface_load, vector_basis)
from pdfem.fem.mesh import load_mesh
from pdfem.fem.stress import centre_basis, element_stress, nodal_average, von_mises

L, H, W = 1.0, 0.1, 0.08
STEEL = ElasticMaterial(density=7850.0, youngs_modulus=210e9, poisson_ratio=0.3)


def write_box(gmsh_box, path, n=(10, 2, 2), hexa=False, size=0.04, version=4.1, order=1, extra=False):
    """Box [0,L]x[0,H]x[0,W] with groups beam (3; also beam_copy when ``extra``), root (x=0),
    tip (x=L), top (z=W), outer (all six faces); hexahedra (n per axis) when ``hexa``, else
    tetrahedra of ``size``."""
    return gmsh_box(path, (L, H, W), volume_groups=["beam", "beam_copy"] if extra else ["beam"],
                    face_groups={"root": ["x0"], "tip": ["x1"], "top": ["z1"],
                                 "outer": ["x0", "x1", "y0", "y1", "z0", "z1"]},
                    divisions=n if hexa else None, size=size, msh_version=version, order=order)


def write_cells(path, points, cells):
    """MSH 2.2 file with the given meshio cells, all in one volume group 'solid'."""
    mesh = meshio.Mesh(np.asarray(points, float), cells,
                       cell_data={"gmsh:physical": [np.ones(len(c[1]), int) for c in cells],
                                  "gmsh:geometrical": [np.ones(len(c[1]), int) for c in cells]},
                       field_data={"solid": np.array([1, 3])})
    meshio.write(str(path), mesh, file_format="gmsh22", binary=False)
    return path


@pytest.fixture(scope="module")
def tet41(tmp_path_factory, gmsh_box):
    return load_mesh(write_box(gmsh_box, tmp_path_factory.mktemp("m") / "t41.msh"))


@pytest.fixture(scope="module")
def hex41(tmp_path_factory, gmsh_box):
    return load_mesh(write_box(gmsh_box, tmp_path_factory.mktemp("m") / "h41.msh", hexa=True, n=(10, 2, 2)))


@pytest.mark.parametrize("version", [4.1, 2.2])
def test_groups_are_read_from_msh_41_and_22(tmp_path, gmsh_box, version):
    """Both MSH versions give the same groups; facets of 'root' lie on x = 0 and cover its area
    H x W; an element listed in two volume groups (MSH 2.2 writes it twice) is kept once
    (reference: the box geometry, volume L H W)."""
    m = load_mesh(write_box(gmsh_box, tmp_path / "b.msh", version=version, extra=True))
    assert m.kind == "tet"
    assert set(m.group_names) == {"beam", "beam_copy", "root", "tip", "top", "outer"}
    assert element_volumes(m).sum() == pytest.approx(L * H * W, rel=1e-12)
    assert len(m.group_elements("beam")) == m.n_elements == len(m.group_elements("beam_copy"))
    assert len(m.group_nodes("beam")) == m.n_nodes
    x = m.points
    assert np.all(x[m.group_nodes("root"), 0] == 0.0)
    assert np.all(x[m.group_nodes("tip"), 0] == pytest.approx(L))
    f = m.group_facets("root")
    tri = x[f]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    assert area.sum() == pytest.approx(H * W, rel=1e-12)
    # skfem facet indices refer to the same faces
    sk = np.sort(m.mesh.facets[:, m.group_facet_indices("root")].T, axis=1)
    assert np.array_equal(sk, np.sort(f, axis=1))


@pytest.mark.parametrize("which", ["tet41", "hex41"])
def test_boundary_facets_point_outward(which, request):
    """Every face of the 'outer' group has its right-hand normal pointing away from the box
    centre (reference: outward normals of a convex box)."""
    m = request.getfixturevalue(which)
    f = m.group_facets("outer")
    x = m.points[f]
    n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    c = np.array([L / 2, H / 2, W / 2])
    assert np.all(np.einsum("ij,ij->i", n, x.mean(axis=1) - c) > 0)
    assert f.shape[1] == (3 if which == "tet41" else 4)


def test_missing_group_lists_the_groups(tet41):
    """A missing name raises ValueError naming the file and listing the groups."""
    with pytest.raises(ValueError, match=r"group 'deck' not in .*t41.msh; the file has groups: "
                                         r"beam, outer, root, tip, top"):
        tet41.group_nodes("deck")
    with pytest.raises(ValueError, match="not a surface group"):
        tet41.group_facets("beam")


def test_mixed_meshes_are_refused(tmp_path):
    """Meshes mixing tetrahedra and hexahedra are refused with a message saying what is
    supported (second-order meshes load: tests/fem/test_fem_quadratic.py)."""
    pts = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [0, 1, 1], [1, 1, 1], [1, 0, 1],
           [0, 0, -1]]
    cells = [("hexahedron", np.array([[0, 1, 4, 2, 3, 7, 6, 5]])),
             ("tetra", np.array([[0, 2, 1, 8]]))]
    with pytest.raises(ValueError, match="hexahedron, tetra.*one kind per mesh"):
        load_mesh(write_cells(tmp_path / "mixed.msh", pts, cells))


def test_inverted_elements_are_fixed_and_degenerate_ones_refused(tmp_path):
    """A tetrahedron and a hexahedron given with inverted node order load with positive volume
    (1/6 and 1); a flat tetrahedron is refused (reference: exact volumes)."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    m = load_mesh(write_cells(tmp_path / "inv.msh", pts, [("tetra", np.array([[0, 2, 1, 3]]))]))
    assert element_volumes(m) == pytest.approx([1 / 6])
    x = m.points[m.mesh.t[:, 0]]
    assert np.linalg.det(np.stack([x[1] - x[0], x[2] - x[0], x[3] - x[0]])) > 0
    cube = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                     [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1.0]])
    mirrored = np.array([[4, 5, 6, 7, 0, 1, 2, 3]])  # top face listed first: inside out
    mh = load_mesh(write_cells(tmp_path / "invh.msh", cube, [("hexahedron", mirrored)]))
    assert element_volumes(mh) == pytest.approx([1.0])
    xv = mh.points[mh.mesh.t[HEX_MAPPING[:8], 0]]  # back to gmsh/VTK node order
    for c, (a, b, up) in enumerate([(1, 3, 4), (2, 0, 5), (3, 1, 6), (0, 2, 7)]):
        assert np.linalg.det(np.stack([xv[a] - xv[c], xv[b] - xv[c], xv[up] - xv[c]])) > 0
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.3, 0.3, 0.0]])
    with pytest.raises(ValueError, match="degenerate"):
        load_mesh(write_cells(tmp_path / "flat.msh", flat, [("tetra", np.array([[0, 1, 2, 3]]))]))


@pytest.mark.parametrize("which", ["tet41", "hex41"])
def test_lumped_mass_stiffness_and_rigid_modes(which, request):
    """Lumped masses are all > 0 and sum to rho V per direction; K is symmetric; rigid-body
    translations and (infinitesimal) rotations give zero force (reference: linear elasticity's
    rigid-body invariance, mass conservation)."""
    m = request.getfixturevalue(which)
    b = vector_basis(m)
    d = DofMap(b.nodal_dofs)
    K = stiffness_matrix(b, STEEL)
    mass = lumped_mass(b, STEEL.density)
    assert np.all(mass > 0)
    assert d.to_nodal(mass).sum(axis=0) == pytest.approx([7850.0 * L * H * W] * 3, rel=1e-12)
    assert abs(K - K.T).max() <= 1e-12 * abs(K).max()
    x = m.points
    scale = abs(K).max() * np.abs(x).max()
    for u in ([1.0, -2.0, 0.5] + 0 * x, np.cross([0.3, -0.2, 0.7], x)):
        assert np.abs(K @ d.to_dofs(u)).max() <= 1e-12 * scale
    # a stretch does produce forces (K is not trivially zero): a tension test
    u = np.zeros_like(x)
    u[:, 0] = 1e-4 * x[:, 0]
    assert np.abs(K @ d.to_dofs(u)).max() > 1e-3 * scale * 1e-4


def test_dof_map_round_trip_and_order(tet41):
    """DofMap reads skfem's ElementVector order (interleaved) and converts both ways."""
    b = vector_basis(tet41)
    d = DofMap(b.nodal_dofs)
    assert d.interleaved
    a = np.arange(3 * tet41.n_nodes, dtype=float).reshape(-1, 3)
    assert np.array_equal(d.to_nodal(d.to_dofs(a)), a)
    assert np.array_equal(d.dofs_of([2], components=(1,)), [b.nodal_dofs[1, 2]])
    blocked = DofMap(np.arange(3 * tet41.n_nodes).reshape(3, -1))
    assert not blocked.interleaved
    assert np.array_equal(blocked.to_nodal(blocked.to_dofs(a)), a)
    assert blocked.to_dofs(a)[tet41.n_nodes] == a[0, 1]


@pytest.mark.parametrize("which", ["tet41", "hex41"])
def test_surface_loads_sum_to_pressure_times_area(which, request):
    """A pressure p on the tip face gives a total force -p n A = (-p H W, 0, 0); a traction t on
    the top face gives t L H; a uniform pressure on the closed outer surface sums to zero
    (references: integral of a uniform traction; divergence theorem)."""
    m = request.getfixturevalue(which)
    d = DofMap(vector_basis(m).nodal_dofs)
    p = 2.0e5
    tip = d.to_nodal(surface_load(m, "tip", pressure=p)).sum(axis=0)
    assert tip == pytest.approx([-p * H * W, 0.0, 0.0], abs=1e-9 * p * H * W)
    top = d.to_nodal(surface_load(m, "top", traction=(0.0, 3.0, -4.0))).sum(axis=0)
    assert top == pytest.approx([0.0, 3.0 * L * H, -4.0 * L * H], abs=1e-12)
    outer = d.to_nodal(surface_load(m, "outer", pressure=p)).sum(axis=0)
    assert np.abs(outer).max() <= 1e-9 * p * H * W


@pytest.mark.parametrize("which", ["tet41", "hex41"])
def test_constant_strain_patch_test(which, request):
    """A linear displacement field u = G x gives exactly sigma = C : sym(G) in every element, its
    von Mises value, and the same nodal average (reference: the FE patch test)."""
    m = request.getfixturevalue(which)
    G = np.array([[1.0, 0.3, -0.2], [0.1, -0.5, 0.4], [0.0, 0.2, 0.7]]) * 1e-4
    u = m.points @ G.T
    d = DofMap(vector_basis(m).nodal_dofs)
    sig = element_stress(centre_basis(m), d.to_dofs(u), STEEL)
    eps = 0.5 * (G + G.T)
    lam, mu = STEEL.lame
    exact = lam * np.trace(eps) * np.eye(3) + 2 * mu * eps
    assert np.abs(sig - exact).max() <= 1e-8 * np.abs(exact).max()
    s = exact - np.trace(exact) / 3 * np.eye(3)
    vm = np.sqrt(1.5 * np.sum(s * s))
    assert von_mises(sig) == pytest.approx(vm, rel=1e-9)
    nod = nodal_average(m, von_mises(sig), element_volumes(m))
    assert nod == pytest.approx(vm, rel=1e-9)
    # uniaxial stress check of von_mises itself: sigma = diag(s, 0, 0) -> s
    assert von_mises(np.diag([5.0, 0.0, 0.0])) == pytest.approx(5.0)
