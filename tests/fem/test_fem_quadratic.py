"""Quadratic elements of elastic structures: HRZ mass, thin plates, supports, contact, output.

References: element mass rho V; a clamped and a simply supported square steel plate, 1 m x 12 mm
(first frequency: Leissa, *Vibration of Plates*, NASA SP-160, 1969; centre deflection under
10 kPa: Timoshenko & Woinowsky-Krieger, *Theory of Plates and Shells*, 1959), modelled as the
quarter plate with symmetry planes held by component supports, as in
docs/structures_convergence.md; the meshio / VTK node order of tetra10 and hexahedron20 (VTK
file formats, "VTK_QUADRATIC_TETRA" and "VTK_QUADRATIC_HEXAHEDRON"); conservation of the
impulse that contact shares among a face's nodes.
"""

from __future__ import annotations

import meshio
import numpy as np
import pytest
import scipy.sparse as sp
import skfem
from scipy.sparse.linalg import LinearOperator, eigsh, factorized
from skfem.io.meshio import HEX_MAPPING

from pdfem.coupling.contact import SurfaceContact
from pdfem.fem.elasticity import ElasticMaterial
from pdfem.fem.fe_space import fe_space, hrz_mass
from pdfem.fem.mesh import load_mesh
from pdfem.fem.structure import ElasticStructure
from pdfem.output import ResultsWriter

from support.xdmf import read_xdmf

A, H, Q = 1.0, 0.012, 10e3                      # plate side (m), thickness (m), pressure (Pa)
STEEL = ElasticMaterial(7850.0, 210e9, 0.3)
OMEGA2 = 1e12   # a stand-in omega_max^2 (1/s^2): these tests never take a time step


def _cyclic(p: np.ndarray, quad: np.ndarray) -> np.ndarray:
    """The corners of a planar quad in cyclic order (sorted by angle about its centre)."""
    x = p[quad]
    c = x.mean(axis=0)
    n = np.cross(x[1] - x[0], x[2] - x[0]) + np.cross(x[2] - x[0], x[3] - x[0])
    e1 = (x[0] - c) / np.linalg.norm(x[0] - c)
    e2 = np.cross(n / np.linalg.norm(n), e1)
    return quad[np.argsort(np.arctan2((x - c) @ e2, (x - c) @ e1))]


def write_quarter_plate(path, size: float = 0.025) -> str:
    """Quarter plate [0, A/2]^2 x [-H/2, H/2], one layer of hexahedra of in-plane ``size`` (m),
    written as gmsh 2.2 with groups: plate (3-D); edges (faces x = 0 and y = 0), symx (x = A/2),
    symy (y = A/2), top (z = H/2) (2-D); ss (1-D, bottom edge lines z = -H/2 of x = 0, y = 0)."""
    x = np.linspace(0.0, 0.5 * A, int(round(0.5 * A / size)) + 1)
    m = skfem.MeshHex.init_tensor(x, x, np.array([-0.5 * H, 0.5 * H]))
    p = m.p.T
    tol = 1e-9
    fb = m.facets[:, m.boundary_facets()].T

    def faces(pred):
        return np.array([_cyclic(p, f) for f in fb if pred(p[f])])

    groups = {"edges": faces(lambda q: (q[:, 0] < tol).all() or (q[:, 1] < tol).all()),
              "symx": faces(lambda q: (abs(q[:, 0] - 0.5 * A) < tol).all()),
              "symy": faces(lambda q: (abs(q[:, 1] - 0.5 * A) < tol).all()),
              "top": faces(lambda q: (abs(q[:, 2] - 0.5 * H) < tol).all())}
    e = m.edges.T
    pe = p[e]
    bottom = (abs(pe[:, :, 2] + 0.5 * H) < tol).all(axis=1)
    on_edge = (pe[:, :, 0] < tol).all(axis=1) | (pe[:, :, 1] < tol).all(axis=1)
    lines = e[bottom & on_edge]
    cells = ([("hexahedron", m.t[HEX_MAPPING[:8]].T)] + [("quad", g) for g in groups.values()]
             + [("line", lines)])
    tags = [np.full(len(c[1]), k + 1) for k, c in enumerate(cells)]
    names = ["plate", *groups, "ss"]
    dims = [3, 2, 2, 2, 2, 1]
    meshio.write(str(path), meshio.Mesh(
        p, cells, cell_data={"gmsh:physical": tags, "gmsh:geometrical": tags},
        field_data={n: np.array([k + 1, d]) for k, (n, d) in enumerate(zip(names, dims))}),
        file_format="gmsh22", binary=False)
    return str(path)


@pytest.fixture(scope="module")
def plate_mesh(tmp_path_factory):
    return load_mesh(write_quarter_plate(tmp_path_factory.mktemp("plate") / "quarter.msh"))


def test_hrz_mass_positive_and_sums_to_element_mass():
    """HRZ-lumped masses of distorted TetP2 and HexS2 elements are all > 0 (row sums are not)
    and per direction sum to the element mass rho V."""
    rng = np.random.default_rng(4)
    hexm = skfem.MeshHex.init_tensor(*[np.linspace(0, 1, 3)] * 3)
    hexm = skfem.MeshHex(hexm.p + 0.05 * rng.standard_normal(hexm.p.shape), hexm.t)
    for mesh, elem in ((hexm, skfem.ElementHexS2()), (hexm.to_meshtet(), skfem.ElementTetP2())):
        basis = skfem.Basis(mesh, skfem.ElementVector(elem), intorder=4)
        m = hrz_mass(basis, STEEL.density)
        assert m.min() > 0.0
        volume = skfem.Basis(mesh, elem, intorder=4).dx.sum()
        for idx in basis.split_indices():
            assert m[idx].sum() == pytest.approx(STEEL.density * volume, rel=1e-12)
        single = skfem.Basis(mesh, skfem.ElementVector(elem), intorder=4, elements=[0])
        rows = np.asarray(skfem.asm(skfem.BilinearForm(
            lambda u, v, w: STEEL.density * (u[0] * v[0] + u[1] * v[1] + u[2] * v[2])),
            single).sum(axis=1)).ravel()
        assert rows[single.element_dofs[:, 0]].min() < 0.0   # why HRZ and not row sums


def _plate(mesh, support: str):
    supports = {"symx": ["x"], "symy": ["y"]}
    fixed = ["edges"] if support == "clamped" else []
    if support == "simply_supported":
        supports["ss"] = ["z"]
    return ElasticStructure(mesh, STEEL, fixed_groups=fixed, supports=supports,
                            contact_group="top", max_eigenvalue=OMEGA2)


@pytest.mark.parametrize("support, f_ref, w_ref", [("clamped", 107.57, 0.3792e-3),
                                                   ("simply_supported", 59.006, 1.2218e-3)])
def test_quarter_plate_frequency_and_deflection(plate_mesh, support, f_ref, w_ref):
    """Default elements (HexS2, one 25 mm layer): f1 within 3 % of Leissa (1969), centre
    deflection under 10 kPa within 5 % of Timoshenko & Woinowsky-Krieger (1959)."""
    s = _plate(plate_mesh, support)
    assert s.cell_type == "hexahedron20" and "HexS2" in s.describe()
    free = np.setdiff1d(np.arange(s.dofmap.n_dofs), s.solver.fixed)
    solve = factorized(s.K[free][:, free].tocsc())
    s.add_surface_load("top", pressure=Q)
    u = np.zeros(s.dofmap.n_dofs)
    u[free] = solve(s.external_force_dofs()[free])
    centre = np.linalg.norm(s.points[:, :2] - 0.5 * A, axis=1) < 1e-9
    w = -s.dofmap.to_nodal(u)[centre, 2].mean()
    op = LinearOperator((free.size, free.size), matvec=solve)
    lam = eigsh(s.K[free][:, free], k=1, M=sp.diags(s.mass[free]), sigma=0.0, which="LM",
                OPinv=op)[0][0]
    f1 = np.sqrt(lam) / (2.0 * np.pi)
    print(f"{support}: f1 = {f1:.3f} Hz (ref {f_ref}), w = {w * 1e3:.4f} mm (ref {w_ref * 1e3})")
    assert f1 == pytest.approx(f_ref, rel=0.03)
    assert w == pytest.approx(w_ref, rel=0.05)


def test_component_supports_hold_only_their_components(plate_mesh):
    """Under pressure, the symmetry-plane nodes keep u_x = 0 (symx) but move in z; the
    reaction of a component support has only its component; the simple support's nodes
    include the midside nodes of its lines."""
    s = _plate(plate_mesh, "simply_supported")
    ss = s.group_nodes("ss")
    assert len(ss) > len(plate_mesh.group_nodes("ss"))            # midside nodes included
    assert np.allclose(s.points[ss, 2], -0.5 * H)
    s.add_surface_load("top", pressure=Q)
    s.set_state()
    dt = 1e-7   # below the critical step of this mesh (about 5.9e-7 s)
    for _ in range(50):
        s.step(dt)
    u = s.displacement()
    symx = s.group_nodes("symx")
    assert np.all(u[symx, 0] == 0.0) and np.abs(u[symx, 2]).max() > 0.0
    assert np.all(u[ss, 2] == 0.0) and np.abs(u[ss, 0]).max() > 0.0
    hist = s.frame_history()
    assert hist["reaction_symx"][1:].tolist() == [0.0, 0.0] and hist["reaction_symx"][0] != 0.0
    assert hist["reaction_ss"][:2].tolist() == [0.0, 0.0] and hist["reaction_ss"][2] != 0.0


def test_vtk_node_order_of_one_element():
    """The midside nodes of output cells sit at the midpoints of the VTK edges: tetra10 nodes
    4-9 on (0,1), (1,2), (0,2), (0,3), (1,3), (2,3); hexahedron20 nodes 8-19 on (0,1), (1,2),
    (2,3), (3,0), (4,5), (5,6), (6,7), (7,4), (0,4), (1,5), (2,6), (3,7)."""
    from pdfem.fem.mesh import FEMesh
    edges = {"tet": [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)],
             "hex": [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
                     (0, 4), (1, 5), (2, 6), (3, 7)]}
    rng = np.random.default_rng(0)
    for kind, m in (("tet", skfem.MeshTet()), ("hex", skfem.MeshHex())):
        m = type(m)(m.p + 0.05 * rng.standard_normal(m.p.shape), m.t)
        space = fe_space(FEMesh(mesh=m, path="<one>", kind=kind), 2)
        c = space.cells()[0]
        x = space.points
        mid = np.array([0.5 * (x[c[a]] + x[c[b]]) for a, b in edges[kind]])
        assert x[c[len(c) - len(mid):]] == pytest.approx(mid, abs=1e-14)
        if kind == "hex":   # VTK corners: bottom 0-3 counter-clockwise seen from above (+z)
            assert np.array_equal(c[:8], m.t[HEX_MAPPING[:8], 0])


def test_contact_impulse_reaches_midside_nodes(plate_mesh):
    """A particle pressed on the centre of a quadratic (8-node) top face: its impulse goes to
    the face's nodes, the shares sum to the impulse exactly and reach the midside nodes."""
    s = _plate(plate_mesh, "clamped")
    con = SurfaceContact(s, search_radius=0.004)
    face = plate_mesh.group_facets("top")[40]
    centre = s.points[face].mean(axis=0)
    y_old = centre[None, :] + [[0.0, 0.0, 0.001]]
    v = np.array([[0.0, 0.0, -2.0]])
    y = y_old + 1e-3 * v
    step = con.resolve(y, y_old, v, np.array([3.0]), 1e-3)
    assert step.contacts == 1
    shares = con.node_impulse
    assert shares.sum(axis=0) == pytest.approx(step.impulse, rel=1e-12)
    # Eq. (5) with the face's inertia: against a rigid face v_bar = (surface - y_old) / dt =
    # -1 m/s and the face would get -m (v_bar - v) = -3 N s; a face that gives way takes less,
    # and exactly what the particle lost (momentum)
    assert -3.0 < step.impulse[2] < 0.0 and step.impulse[:2] == pytest.approx([0, 0], abs=1e-12)
    assert 3.0 * (v[0, 2] + 2.0) == pytest.approx(-step.impulse[2], rel=1e-12)
    hit = s.surface_nodes[np.abs(shares).sum(axis=1) > 0]
    midside = set(s.space.face_nodes(face[None, :])[0, 4:])
    assert set(hit) <= midside | set(face) and set(hit) & midside


def test_xdmf_of_quadratic_mesh_round_trips(plate_mesh, tmp_path):
    """A HexS2 structure written by the results writer reads back through its XDMF file
    (tests/support/xdmf.py) as Hexahedron_20 cells with the same points, u and v."""
    s = _plate(plate_mesh, "clamped")
    rng = np.random.default_rng(2)
    s.set_state(displacement=1e-6 * rng.standard_normal((s.n_nodes, 3)),
                velocity=1e-3 * rng.standard_normal((s.n_nodes, 3)))
    points, cells, cell_type = s.output_mesh()
    fields = s.output_fields()
    with ResultsWriter(tmp_path / "r.h5") as w:
        w.add_structure("plate", points, cells, cell_type)
        w.write_frame(0.0, {}, {"plate": fields})
    grid = read_xdmf(tmp_path / "r.xdmf")["structure/plate"][0].grids["structure/plate"]
    assert grid.topology == "Hexahedron_20"
    np.testing.assert_array_equal(grid.cells, cells)
    np.testing.assert_array_equal(grid.points, points + fields["u"])
    for name in ("u", "v"):
        np.testing.assert_array_equal(grid.point_data[name], fields[name])


def test_second_order_gmsh_tet_file_is_isoparametric(tmp_path, gmsh_box):
    """A gmsh tetra10 mesh loads isoparametric; the structure's FE nodes are the file's nodes
    and describe() says how it was read."""
    path = gmsh_box(tmp_path / "p2.msh", (0.3, 0.2, 0.1), volume_groups=["block"],
                    face_groups={"contact": ["z1"], "fixed": ["x0"]}, size=0.05, order=2)
    mesh = load_mesh(path)
    assert mesh.file_order == 2
    s = ElasticStructure(mesh, STEEL, fixed_groups=["fixed"], contact_group="contact",
                         max_eigenvalue=OMEGA2)
    raw = meshio.read(path)
    used = np.unique(raw.cells_dict["tetra10"])
    key = lambda x: np.round(x, 9)[np.lexsort(np.round(x, 9).T)]  # noqa: E731
    assert s.n_nodes == len(used)
    np.testing.assert_allclose(key(s.points), key(raw.points[used]), atol=1e-9)
    assert mesh.isoparametric and "isoparametric" in s.describe()
    assert s.cell_type == "tetra10"


def test_isoparametric_tetra10_keeps_a_curved_boundary(tmp_path):
    """A sphere of radius 1 m meshed by gmsh with tetra10: the isoparametric volume is much
    closer to 4/3 pi than the straight-sided corner mesh's (reference: sphere volume)."""
    import gmsh

    from pdfem.fem.elasticity import element_volumes
    path = str(tmp_path / "sphere.msh")
    gmsh.initialize(["-v", "0"])
    try:
        gmsh.model.occ.addSphere(0, 0, 0, 1.0)
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [1], name="ball")
        gmsh.model.addPhysicalGroup(2, [1], name="skin")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.5)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(2)
        gmsh.write(path)
    finally:
        gmsh.finalize()
    mesh = load_mesh(path)
    exact = 4.0 / 3.0 * np.pi
    iso = element_volumes(mesh).sum()
    flat = skfem.Basis(skfem.MeshTet1(mesh.points.T, mesh.mesh.t), skfem.ElementTetP1()).dx.sum()
    print(f"sphere volume: isoparametric {iso:.5f}, straight {flat:.5f}, exact {exact:.5f}")
    assert abs(iso - exact) < 0.1 * abs(flat - exact)
    s = ElasticStructure(mesh, STEEL, contact_group="skin", max_eigenvalue=OMEGA2)
    r = np.linalg.norm(s.points[s.surface_nodes], axis=1)
    assert r == pytest.approx(np.ones_like(r), abs=1e-6)       # midside nodes on the sphere


def test_hexahedron27_file_is_read_by_its_corners(tmp_path, gmsh_box):
    """A gmsh hexahedron27 mesh with quad9 faces loads as HexS2: its FE nodes are the file's
    corner and edge nodes (face and body centres dropped) and the contact group has 8 nodes per
    face."""
    path = gmsh_box(tmp_path / "h27.msh", (0.3, 0.2, 0.1), volume_groups=["block"],
                    face_groups={"contact": ["z1"], "fixed": ["x0"]}, divisions=(3, 2, 1),
                    order=2)
    mesh = load_mesh(path)
    raw = meshio.read(path)
    assert "hexahedron27" in raw.cells_dict and mesh.file_order == 2
    s = ElasticStructure(mesh, STEEL, fixed_groups=["fixed"], contact_group="contact",
                         max_eigenvalue=OMEGA2)
    used = np.unique(raw.cells_dict["hexahedron27"])
    assert s.cell_type == "hexahedron20"
    assert s.n_nodes == len(used) - mesh.mesh.facets.shape[1] - mesh.n_elements
    file_pts = {tuple(x) for x in np.round(raw.points[used], 9)}
    assert all(tuple(x) in file_pts for x in np.round(s.points, 9))
    # top face, 3 x 2 quads: 4 x 3 corners + (3 x 3 + 2 x 4) edge midpoints
    assert len(s.surface_nodes) == len(s.group_nodes("contact")) == 12 + 17


def test_case_supports_and_element_order():
    """The case fields: supports per component resolve to (group, components); a component
    other than x, y, z and an element_order other than 1 or 2 are refused naming the field."""
    from pathlib import Path

    from pdfem.case.loader import parse_case
    from pdfem.errors import InputError
    models = Path(__file__).resolve().parents[2] / "models"
    text = (models / "demo_ice_sheet_panel.toml").read_text()
    old = 'fixed_groups = ["fixed"]'

    def case(extra: str):
        return parse_case(text.replace(old, f"{old}\n{extra}"), "demo.toml", models)

    cfg = case('supports = [{ group = "contact", components = ["z", "x"] }]').structures[0]
    assert cfg.supports == (("contact", ("z", "x")),) and cfg.element_order == 2
    with pytest.raises(InputError, match=r"supports\[0\]\.components.*\"x\", \"y\", \"z\""):
        case('supports = [{ group = "contact", components = ["w"] }]')
    with pytest.raises(InputError, match="element_order.*1 .*or 2"):
        case("element_order = 3")


def test_quadratic_element_stress_of_a_uniaxial_stretch(plate_mesh):
    """A uniaxial stress state (u_x = e x, u_y = u_z = -nu e y, -nu e z) interpolated exactly
    by HexS2 gives sigma_xx = E e and von Mises E e in every element (Hooke's law)."""
    s = _plate(plate_mesh, "clamped")
    e, nu = 1e-4, STEEL.poisson_ratio
    x = s.points
    s.solver.u[:] = s.dofmap.to_dofs(np.column_stack([e * x[:, 0], -nu * e * x[:, 1],
                                                      -nu * e * x[:, 2]]))
    sig = s.stresses()
    assert sig[:, 0, 0] == pytest.approx(np.full(len(sig), STEEL.youngs_modulus * e), rel=1e-9)
    assert s.von_mises() == pytest.approx(np.full(len(sig), STEEL.youngs_modulus * e), rel=1e-9)
    assert s.nodal_von_mises().shape == (s.n_nodes,)
