"""Hexahedral and second-order meshes from model scripts: the structured hull panel (conforming,
groups, counts from its grid), finish_mesh with tetra10 / hexahedron20 / hexahedron27 meshes
read back with meshio, and the validation box's face and edge-line groups.

References: the analytic geometry of axis-aligned boxes (areas, volumes, node and cell counts
of a tensor grid), and the definition of a conforming mesh (every interior face shared by
exactly two elements, no node inside another element's face or edge).
"""

from __future__ import annotations

import meshio
import numpy as np
import pytest

from pdfem.meshing import finish_mesh, gmsh_session
from pdfem.meshing.elements import HEX_FACES
from pdfem.models import hull_panel
from pdfem.models.validation import box

PANEL = dict(length=1.0, breadth=0.8, plate_thickness=0.015, stiffener_spacing=0.3, stiffener_height=0.1,
             stiffener_thickness=0.01, frame_spacing=0.5, frame_height=0.2, frame_thickness=0.012,
             frame_flange_width=0.06, frame_flange_thickness=0.014, element_size=0.06, layers=2)


def _block(mesh: meshio.Mesh, group: str, prefix: str) -> np.ndarray:
    blocks = [b.data[idx] for b, idx in zip(mesh.cells, mesh.cell_sets[group])
              if b.type.startswith(prefix) and idx is not None and len(idx)]
    return np.concatenate(blocks)


@pytest.fixture(scope="module")
def panel(tmp_path_factory):
    report = hull_panel.build(tmp_path_factory.mktemp("hex") / "panel.msh", **PANEL)
    return report, meshio.read(report.path)


def test_hex_panel_is_conforming(panel):
    """Every face of a hexahedron is shared with exactly one other hexahedron or lies on the
    boundary, and no mesh node lies inside (or on the faces or edges of) a hexahedron other
    than at its 8 corners: no hanging nodes."""
    report, mesh = panel
    hexes = _block(mesh, "hull", "hexahedron")
    assert hexes.shape[1] == 8 and report.elements["hexahedron"] == len(hexes)
    _, counts = np.unique(np.sort(hexes[:, HEX_FACES].reshape(-1, 4), axis=1), axis=0, return_counts=True)
    assert set(counts) <= {1, 2}
    pts = mesh.points[np.unique(hexes)]
    lo, hi = mesh.points[hexes].min(axis=1), mesh.points[hexes].max(axis=1)
    tol = 1e-9
    for a, b in zip(lo, hi):
        inside = np.all((pts >= a - tol) & (pts <= b + tol), axis=1)
        assert inside.sum() == 8
    # the boundary faces enclose the analytic volume (divergence theorem on the quads)
    faces = np.sort(hexes[:, HEX_FACES].reshape(-1, 4), axis=1)
    _, first, counts = np.unique(faces, axis=0, return_index=True, return_counts=True)
    quads = hexes[:, HEX_FACES].reshape(-1, 4)[first[counts == 1]]
    p = mesh.points
    a, b, c, d = (p[quads[:, k]] for k in range(4))
    normal = 0.5 * np.cross(c - a, d - b)
    centre = 0.25 * (a + b + c + d)
    assert np.einsum("ij,ij->i", normal, centre).sum() / 3 == pytest.approx(hull_panel.hull_volume(**PANEL), rel=1e-9)


def test_hex_panel_groups(panel):
    """contact: the plating face z = 0, area length x breadth, normals +z; fixed: faces on the
    panel's boundary planes x = 0, L or y = 0, B with outward normals along them."""
    report, mesh = panel
    L, B = PANEL["length"], PANEL["breadth"]
    p = mesh.points
    for name, normal_axis in (("contact", None), ("fixed", None)):
        q = _block(mesh, name, "quad")
        a, b, c, d = (p[q[:, k]] for k in range(4))
        n = np.cross(c - a, d - b)
        if name == "contact":
            assert 0.5 * np.linalg.norm(n, axis=1).sum() == pytest.approx(L * B, rel=1e-12)
            assert np.all(n[:, 2] > 0) and np.allclose(p[q][..., 2], 0.0)
        else:
            xyz = p[q].mean(axis=1)
            on_x = np.isclose(xyz[:, 0], 0) | np.isclose(xyz[:, 0], L)
            on_y = np.isclose(xyz[:, 1], 0) | np.isclose(xyz[:, 1], B)
            assert np.all(on_x | on_y)
            out = np.where(on_x, np.sign(xyz[:, 0] - L / 2) * n[:, 0], np.sign(xyz[:, 1] - B / 2) * n[:, 1])
            assert np.all(out > 0)
    assert report.groups == {"hull": 3, "contact": 2, "fixed": 2, "bay1": 2, "bay2": 2}


def test_hex_panel_counts_from_the_grid(tmp_path):
    """A 0.6 x 0.4 m plate (t = 10 mm) with one flat bar (10 mm x 100 mm) at y = 0.2 and 50 mm
    cells: x 12 cells; y 4 + 1 (the bar's thickness) + 4; z 1 in the plate, 2 along the bar.
    Hexahedra 12*9*1 + 12*1*2 = 132; nodes 13*10*2 + 13*2*2 = 312; with layers = 2 the
    thicknesses get 2 cells: 12*10*2 + 12*2*2 = 288 hexahedra, 13*11*3 + 13*3*2 = 507 nodes."""
    common = dict(length=0.6, breadth=0.4, plate_thickness=0.01, stiffener_spacing=0.2, stiffener_height=0.1,
                  stiffener_thickness=0.01, frame_spacing=0.7, element_size=0.05)
    for layers, hexes, nodes in ((1, 132, 312), (2, 288, 507)):
        report = hull_panel.build(tmp_path / f"p{layers}.msh", **common, layers=layers)
        assert report.elements["hexahedron"] == hexes
        assert report.nodes == nodes
        assert report.total_volume == pytest.approx(0.6 * 0.4 * 0.01 + 0.6 * 0.01 * 0.1, rel=1e-12)


@pytest.mark.parametrize("hexa, incomplete, vol_type, face_type", [
    (False, 0, "tetra10", "triangle6"), (True, 1, "hexahedron20", "quad8"), (True, 0, "hexahedron27", "quad9")])
def test_finish_mesh_second_order_round_trip(tmp_path, hexa, incomplete, vol_type, face_type):
    """A 1 x 0.5 x 0.2 m box meshed by gmsh at second order with its boundary given inward:
    finish_mesh turns every face outward (normal away from the box centre), mid-side nodes stay
    the mid-points of their corners, meshio reads the groups, and the volume is 0.1 m^3."""
    out = tmp_path / "b.msh"
    with gmsh_session("b") as gmsh:
        v = gmsh.model.occ.addBox(0, 0, 0, 1, 0.5, 0.2)
        gmsh.model.occ.synchronize()
        faces = [s for _, s in gmsh.model.getEntities(2)]
        gmsh.model.addPhysicalGroup(3, [v], name="solid")
        gmsh.model.addPhysicalGroup(2, faces, name="contact")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.2)
        if hexa:
            for _, c in gmsh.model.getEntities(1):
                gmsh.model.mesh.setTransfiniteCurve(c, 3)
            for s in faces:
                gmsh.model.mesh.setTransfiniteSurface(s)
                gmsh.model.mesh.setRecombine(2, s)
            gmsh.model.mesh.setTransfiniteVolume(v)
        gmsh.option.setNumber("Mesh.SecondOrderIncomplete", incomplete)
        gmsh.model.mesh.generate(3)
        gmsh.model.mesh.setOrder(2)
        gmsh.model.mesh.reverse([(2, s) for s in faces])
        report = finish_mesh(out, "b", {}, 3)
    mesh = meshio.read(out)
    assert {b.type for b in mesh.cells} == {vol_type, face_type}
    assert set(report.elements) == {vol_type, face_type}
    assert report.total_volume == pytest.approx(0.1, rel=1e-12)
    q = _block(mesh, "contact", face_type)
    n = 3 if face_type == "triangle6" else 4
    P = mesh.points[q]
    for k in range(n):
        assert np.allclose(P[:, n + k], 0.5 * (P[:, k] + P[:, (k + 1) % n]))
    normal = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]) if n == 3 else np.cross(P[:, 2] - P[:, 0], P[:, 3] - P[:, 1])
    assert np.all(np.einsum("ij,ij->i", normal, P[:, :n].mean(axis=1) - [0.5, 0.25, 0.1]) > 0)
    assert 0.5 * np.linalg.norm(normal, axis=1).sum() == pytest.approx(2 * (0.5 + 0.2 + 0.1))


@pytest.mark.parametrize("divisions", [4, 0])
def test_box_face_and_edge_line_groups(tmp_path, divisions):
    """A quarter plate 0.5 x 0.5 x 0.012 m: the edge-line group x0z0+y0z0 holds exactly the
    nodes with z = 0 and x = 0 or y = 0 (with 4 x 4 hexahedra: 5 + 5 - 1 = 9 nodes), the face
    groups x1, y1 lie on their planes, and faces can be in two groups (x0 in fixed and edge_x)."""
    report = box.build(tmp_path / "q.msh", length_x=0.5, length_y=0.5, length_z=0.012, divisions_x=divisions,
                       divisions_y=4, divisions_z=1, element_size=0.1, fixed_faces="x0", contact_faces="z1",
                       groups="sym_x:x1, sym_y:y1, support:x0z0+z0y0, edge_x:x0")
    assert report.groups["support"] == 1 and report.groups["sym_x"] == 2
    mesh = meshio.read(report.path)
    p = mesh.points
    nodes = np.unique(_block(mesh, "support", "line"))
    want = np.flatnonzero(np.isclose(p[:, 2], 0) & (np.isclose(p[:, 0], 0) | np.isclose(p[:, 1], 0)))
    used = np.unique(np.concatenate([b.data.ravel() for b in mesh.cells if b.type in ("tetra", "hexahedron")]))
    assert set(nodes) == set(want) & set(used)
    if divisions:
        assert len(nodes) == 9
    assert np.allclose(p[np.unique(_block(mesh, "sym_x", "quad" if divisions else "triangle")), 0], 0.5)
    assert np.allclose(p[np.unique(_block(mesh, "sym_y", "quad" if divisions else "triangle")), 1], 0.5)
    assert len(_block(mesh, "edge_x", "")) == len(_block(mesh, "fixed", ""))


@pytest.mark.parametrize("groups", ["a:x2", "a:x0x1", "a:x0+x0z0", "solid:x0", "a"])
def test_box_bad_groups(tmp_path, groups):
    """Unknown faces, edges of parallel faces, mixtures and reserved names are refused, named."""
    from pdfem.meshing import ModelParameterError
    with pytest.raises(ModelParameterError) as info:
        box.build(tmp_path / "x.msh", groups=groups)
    assert info.value.param == "groups"


def test_finish_mesh_refuses_triangles_on_a_hexahedral_mesh(tmp_path):
    """A surface group of triangles on a hexahedron (whose faces are quadrilaterals) is refused
    by name, and no file is written."""
    from pdfem.meshing import MeshQualityError
    from pdfem.meshing.structured import add_discrete_mesh
    nodes = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    with gmsh_session("h") as gmsh:
        add_discrete_mesh(gmsh, nodes, np.arange(8)[None], "solid", {})
        s = gmsh.model.addDiscreteEntity(2)
        gmsh.model.mesh.addElementsByType(s, 2, [], [1, 4, 3, 1, 3, 2])
        gmsh.model.addPhysicalGroup(2, [s], name="bottom")
        with pytest.raises(MeshQualityError, match="quad"):
            finish_mesh(tmp_path / "h.msh", "h", {}, 3)
    assert not (tmp_path / "h.msh").exists()


def test_model_meshes_load_in_the_structure_reader(panel, tmp_path):
    """End to end: the hexahedral panel and the second-order blade load with pdfem.fem.mesh
    (hexahedra, resp. tetrahedra with their mid-side nodes), with every group; the panel's
    contact facets are its quadrilaterals of total area length x breadth."""
    from pdfem.fem.mesh import load_mesh
    from pdfem.models import propeller_blade
    report, mesh = panel
    fm = load_mesh(report.path)
    assert fm.kind == "hex" and set(fm.facet_sets) >= {"contact", "fixed"}
    q = fm.facet_sets["contact"]
    p = fm.points
    area = 0.5 * np.linalg.norm(np.cross(p[q[:, 2]] - p[q[:, 0]], p[q[:, 3]] - p[q[:, 1]]), axis=1).sum()
    assert area == pytest.approx(PANEL["length"] * PANEL["breadth"], rel=1e-12)
    blade = propeller_blade.build(tmp_path / "b.msh", element_size=0.06)
    assert set(blade.elements) == {"tetra10", "triangle6"}
    fb = load_mesh(blade.path)
    assert fb.kind == "tet" and set(fb.facet_sets) == {"contact", "root"}
