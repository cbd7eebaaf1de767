"""Tests of the parametric gmsh models (hull panel, propeller blade, indenters) and pdfem.meshing.runner.

Every mesh is read back with meshio (an independent reader) and checked against analytic
geometry: volumes and areas of the parts, the NACA 00xx section area, the divergence theorem
for closed surfaces, and the dihedral angles of a regular tetrahedron.
"""

from __future__ import annotations

import math

import meshio
import numpy as np
import pytest
from scipy.integrate import quad

from pdfem.errors import InputError
from pdfem.meshing import (MeshQualityError, ModelParameterError, coerce_parameters, finish_mesh, gmsh_session,
                           parse_set)
from pdfem.meshing.quality import tet_inradii, tet_min_dihedral, triangle_min_angle
from pdfem.meshing.runner import available_models, mesh_model, resolve_model
from pdfem.models import hull_panel, indenters, propeller_blade


# ------------------------------------------------------------------------------------- helpers

def _cells(mesh: meshio.Mesh, group: str, cell_type: str) -> np.ndarray:
    """Corner connectivity of the group's cells of ``cell_type`` or its quadratic variants
    (tetra10 for tetra, triangle6 for triangle: gmsh lists the corners first)."""
    n = {"triangle": 3, "tetra": 4, "quad": 4, "hexahedron": 8}[cell_type]
    blocks = [b.data[idx][:, :n] for b, idx in zip(mesh.cells, mesh.cell_sets[group])
              if b.type.rstrip("0123456789") == cell_type and idx is not None and len(idx)]
    return np.concatenate(blocks) if blocks else np.zeros((0, n), int)


def _tet_volumes(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    a, b, c, d = (p[t[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0


def _tri_normals(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Area-weighted normals (length = 2 x area), right-hand rule on the node order; of a planar
    quadrilateral (4 columns), the cross product of its diagonals (also 2 x area)."""
    if t.shape[1] == 4:
        a, b, c, d = (p[t[:, k]] for k in range(4))
        return np.cross(c - a, d - b)
    a, b, c = (p[t[:, k]] for k in range(3))
    return np.cross(b - a, c - a)


def _box_volumes(p: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Volumes of axis-aligned box hexahedra in gmsh order: (x1-x0)(y3-y0)(z4-z0), signed."""
    return ((p[h[:, 1], 0] - p[h[:, 0], 0]) * (p[h[:, 3], 1] - p[h[:, 0], 1])
            * (p[h[:, 4], 2] - p[h[:, 0], 2]))


def _divergence_volume(p: np.ndarray, t: np.ndarray) -> float:
    """Volume enclosed by an outward-oriented closed triangle surface (divergence theorem)."""
    a, b, c = (p[t[:, k]] for k in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def _assert_closed_and_oriented(t: np.ndarray) -> None:
    """Every edge in exactly two triangles, traversed once in each direction."""
    directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    _, counts = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    assert np.all(counts == 2), "open or non-manifold surface"
    _, dcounts = np.unique(directed, axis=0, return_counts=True)
    assert np.all(dcounts == 1), "inconsistently oriented surface"


def _groups(mesh: meshio.Mesh) -> dict[str, int]:
    return {name: int(v[1]) for name, v in mesh.field_data.items()}


# ------------------------------------------------------------------------------------- every model

HULL_PARAMS = dict(length=1.0, breadth=0.8, plate_thickness=0.015, stiffener_spacing=0.3, stiffener_height=0.1,
                   stiffener_thickness=0.01, frame_spacing=0.5, frame_height=0.2, frame_thickness=0.012,
                   frame_flange_width=0.06, frame_flange_thickness=0.014, element_size=0.06)
BLADE_PARAMS = dict(radius=1.0, hub_radius=0.3, max_chord=0.5, max_chord_radius=0.6, tip_chord=0.15,
                    root_thickness=0.07, tip_thickness=0.015, pitch=1.4, skew_angle=0.35, element_size=0.05)

#: every model in models/: parameters for a coarse mesh, and the physical groups (name -> dim) it must have
MODEL_CASES = {
    "hull_panel": (HULL_PARAMS, {"hull": 3, "contact": 2, "fixed": 2, "bay1": 2, "bay2": 2}),
    "propeller_blade": (BLADE_PARAMS, {"blade": 3, "contact": 2, "root": 2}),
    "indenters": (dict(shape="sphere", element_size=0.25), {"contact": 2}),
    "propeller": (dict(blades=2, element_size=0.12, sections=6),
                  {"root": 2, "contact": 2, **{f"blade{k}": 3 for k in (1, 2)},
                   **{f"blade{k}_{s}": 2 for k in (1, 2) for s in ("root", "leading_edge", "trailing_edge", "tip",
                                                                  "face", "back", "surface")}}),
    "icebreaker": (dict(element_size=0.1), {"bow": 2, "shoulder": 2, "midship": 2, "stern": 2,
                                            "bow_panel": 2, "contact": 2}),
    "bow_panel": ({}, {"hull": 3, "contact": 2, "fixed": 2, "bay1": 2, "bay2": 2}),
}


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """Factory: the model ``name`` meshed once per module with its MODEL_CASES parameters;
    returns (MeshReport, the file read back with meshio)."""
    folder = tmp_path_factory.mktemp("models")
    cache = {}

    def get(name: str) -> tuple:
        if name not in cache:
            report = resolve_model(name).build(folder / f"{name}.msh", **MODEL_CASES[name][0])
            cache[name] = (report, meshio.read(report.path))
        return cache[name]
    return get


@pytest.mark.parametrize("name", available_models())
def test_every_model_meshes_coarsely_with_all_its_groups(name, built):
    """Each model in models/ meshes at a coarse size; every physical group it documents is in
    the file and holds elements, and every tetrahedron (triangle, for a surface mesh) has positive
    volume (area), recomputed from the file read back with meshio (reference: signed volume of a
    simplex, independent of pdfem.meshing.runner)."""
    assert name in MODEL_CASES, f"model '{name}' has no coarse test case in MODEL_CASES"
    report, mesh = built(name)
    groups = MODEL_CASES[name][1]
    assert _groups(mesh) == groups
    assert report.groups == groups
    hexa = any(t.startswith("hexahedron") for t in report.elements)
    for group, dim in groups.items():
        cells = _cells(mesh, group, ("hexahedron" if hexa else "tetra") if dim == 3 else ("quad" if hexa else "triangle"))
        assert len(cells) > 0, group
        if dim == 3 and not hexa:
            assert np.all(_tet_volumes(mesh.points, cells) > 0)
        elif dim == 3:
            assert np.all(_box_volumes(mesh.points, cells) > 0)
        else:
            assert np.all(np.linalg.norm(_tri_normals(mesh.points, cells), axis=1) > 0)
    assert report.min_volume > 0 and report.min_sicn > 0


# ------------------------------------------------------------------------------------- hull panel

@pytest.mark.parametrize("element_type", ["hex", "tet"])
def test_hull_panel_volume_areas_and_groups(built, tmp_path, element_type):
    """Reference: analytic volumes and areas of the boxes the panel is made of.

    hull volume = plate + stiffeners + frames (web and flange) - stiffener/frame crossings;
    contact area = length x breadth (normals +z, out of the steel toward the ice);
    fixed area = plate edges + stiffener and frame end faces.
    """
    p = HULL_PARAMS
    if element_type == "hex":
        report, mesh = built("hull_panel")
    else:
        report = hull_panel.build(tmp_path / "tet.msh", **HULL_PARAMS, element_type="tet")
        mesh = meshio.read(report.path)
    vtype, ftype = ("hexahedron", "quad") if element_type == "hex" else ("tetra", "triangle")
    groups = {"hull": 3, "contact": 2, "fixed": 2}
    if element_type == "hex":  # the contact surface split at the frame (x = 0.5) into bays
        groups.update(bay1=2, bay2=2)
    assert _groups(mesh) == groups
    assert report.groups == groups

    pts = mesh.points
    tets = _cells(mesh, "hull", vtype)
    vol = (_box_volumes if element_type == "hex" else _tet_volumes)(pts, tets)
    assert np.all(vol > 0)
    n_s, n_f = 2, 1                                   # stiffeners at y = 0.25, 0.55; frame at x = 0.5
    L, B = p["length"], p["breadth"]
    expected = (L * B * p["plate_thickness"]
                + n_s * L * p["stiffener_thickness"] * p["stiffener_height"]
                + n_f * B * (p["frame_thickness"] * p["frame_height"]
                             + p["frame_flange_width"] * p["frame_flange_thickness"])
                - n_s * n_f * p["stiffener_thickness"] * p["frame_thickness"] * p["stiffener_height"])
    assert vol.sum() == pytest.approx(expected, rel=1e-6)
    assert report.total_volume == pytest.approx(expected, rel=1e-6)
    assert report.nodes == len(np.unique(tets))
    assert report.elements[vtype] == len(tets)

    contact = _tri_normals(pts, _cells(mesh, "contact", ftype))
    assert 0.5 * np.linalg.norm(contact, axis=1).sum() == pytest.approx(L * B, rel=1e-9)
    assert np.all(contact[:, 2] > 0)                  # the ice side z = 0, normals out of the steel
    assert np.all(np.abs(pts[_cells(mesh, "contact", ftype)][..., 2]) < 1e-12)

    if element_type == "hex":  # frame bays either side of the frame at x = 0.5, tiling the plate
        areas = 0.0
        for bay, side in (("bay1", -1), ("bay2", 1)):
            quads = _cells(mesh, bay, ftype)
            areas += 0.5 * np.linalg.norm(_tri_normals(pts, quads), axis=1).sum()
            centre = pts[quads][..., 0].mean(axis=1) - 0.5
            assert np.all(centre <= 0) if side < 0 else np.all(centre > 0)
        assert areas == pytest.approx(L * B, rel=1e-9)

    fixed = _tri_normals(pts, _cells(mesh, "fixed", ftype))
    fixed_area = (2 * (L + B) * p["plate_thickness"] + 2 * n_s * p["stiffener_thickness"] * p["stiffener_height"]
                  + 2 * n_f * (p["frame_thickness"] * p["frame_height"]
                               + p["frame_flange_width"] * p["frame_flange_thickness"]))
    assert 0.5 * np.linalg.norm(fixed, axis=1).sum() == pytest.approx(fixed_area, rel=1e-9)


def test_hull_panel_without_stiffeners_is_a_plate(tmp_path):
    """Reference: a plate only (spacings >= the panel size): volume L B t, area L B."""
    report = hull_panel.build(tmp_path / "plate.msh", length=0.6, breadth=0.4, plate_thickness=0.02,
                              stiffener_spacing=0.5, frame_spacing=0.7, element_size=0.05)
    assert report.total_volume == pytest.approx(0.6 * 0.4 * 0.02, rel=1e-9)


@pytest.mark.parametrize("bad, param", [
    (dict(stiffener_height=0.3, frame_height=0.3), "stiffener_height"),
    (dict(plate_thickness=-0.01), "plate_thickness"),
    (dict(stiffener_thickness=0.5), "stiffener_thickness"),
    (dict(frame_flange_width=0.005), "frame_flange_width"),
    (dict(element_size=1e-4), "element_size"),
    (dict(length="2"), "length"),
    (dict(width=1.0), "width"),
    (dict(element_type="quad"), "element_type"),
    (dict(layers=0), "layers"),
])
def test_hull_panel_bad_parameters(tmp_path, bad, param):
    """Bad or inconsistent parameters raise ModelParameterError naming the parameter; no file."""
    with pytest.raises(ModelParameterError) as info:
        hull_panel.build(tmp_path / "x.msh", **bad)
    assert info.value.param == param
    assert param in str(info.value)
    assert not (tmp_path / "x.msh").exists()


# ------------------------------------------------------------------------------------- blade

def _naca_area_factor() -> float:
    """Area of the closed-trailing-edge NACA 00xx section / (chord x thickness), by quadrature."""
    def half(x):
        return 5 * (0.2969 * math.sqrt(x) - 0.1260 * x - 0.3516 * x**2 + 0.2843 * x**3 - 0.1036 * x**4)
    return 2 * quad(half, 0.0, 1.0)[0]


def test_blade_root_area_groups_and_closed_surface(built):
    """Reference: the NACA 00xx section area 0.681 c t at the hub (0.685 c t for the open trailing
    edge), with c from the documented elliptic chord law; the divergence theorem for the closed
    root + contact surface versus the sum of tetrahedron volumes."""
    p = BLADE_PARAMS
    report, mesh = built("propeller_blade")
    assert _groups(mesh) == {"blade": 3, "contact": 2, "root": 2}
    pts = mesh.points
    tets = _cells(mesh, "blade", "tetra")
    vol = _tet_volumes(pts, tets)
    assert np.all(vol > 0)

    root = _cells(mesh, "root", "triangle")
    radial = np.hypot(pts[root][..., 1], pts[root][..., 2])
    assert np.allclose(radial, p["hub_radius"], rtol=1e-6)        # OCC edge tolerance
    s = (p["hub_radius"] - p["max_chord_radius"]) / (p["radius"] - p["max_chord_radius"])
    chord = p["max_chord"] * math.sqrt(1 - s * s * (1 - (p["tip_chord"] / p["max_chord"]) ** 2))
    expected = _naca_area_factor() * chord * p["root_thickness"]
    assert _naca_area_factor() == pytest.approx(0.685, rel=0.01)
    area = 0.5 * np.linalg.norm(_tri_normals(pts, root), axis=1).sum()
    assert area == pytest.approx(expected, rel=0.03)

    surface = np.concatenate([root, _cells(mesh, "contact", "triangle")])
    _assert_closed_and_oriented(surface)
    assert _divergence_volume(pts, surface) == pytest.approx(vol.sum(), rel=1e-9)
    # the tip face lies on the cylinder r = R, nothing beyond it (mid-side nodes of the default
    # second-order mesh are projected onto the OCC surface, to its 1e-8 tolerance)
    assert np.hypot(pts[:, 1], pts[:, 2]).max() == pytest.approx(p["radius"], rel=1e-8)
    assert {b.type for b in mesh.cells} == {"tetra10", "triangle6"}
    assert report.min_sicn > 0 and report.min_angle > 0


@pytest.mark.parametrize("bad, param", [
    (dict(hub_radius=1.2), "hub_radius"),
    (dict(max_chord_radius=0.2), "max_chord_radius"),
    (dict(tip_chord=0.6), "tip_chord"),
    (dict(tip_thickness=0.1), "tip_thickness"),
    (dict(sections=2), "sections"),
    (dict(skew_angle=2.0), "skew_angle"),
    (dict(sections=10.5), "sections"),
])
def test_blade_bad_parameters(tmp_path, bad, param):
    """Bad or inconsistent blade parameters raise ModelParameterError naming the parameter."""
    with pytest.raises(ModelParameterError) as info:
        propeller_blade.build(tmp_path / "x.msh", **bad)
    assert info.value.param == param


# ------------------------------------------------------------------------------------- indenters

@pytest.mark.parametrize("params, volume, area", [
    (dict(shape="sphere", radius=0.5, element_size=0.1, center_x=1.0), 4 / 3 * math.pi * 0.5**3, 4 * math.pi * 0.25),
    (dict(shape="cylinder", radius=0.3, length=1.2, axis="x", element_size=0.08, center_z=-0.5),
     math.pi * 0.09 * 1.2, 2 * math.pi * 0.3 * (0.3 + 1.2)),
    (dict(shape="wedge", element_size=0.15), None, None),
])
def test_indenter_closed_surface(tmp_path, params, volume, area):
    """Reference: analytic volumes (sphere 4/3 pi r^3, cylinder pi r^2 L, wedge the integral of its
    triangular horizontal sections) against the divergence theorem on the written surface, which
    must be closed and consistently oriented outward."""
    report = indenters.build(tmp_path / "ind.msh", **params)
    mesh = meshio.read(tmp_path / "ind.msh")
    assert _groups(mesh) == {"contact": 2}
    tris = _cells(mesh, "contact", "triangle")
    assert len(tris) == sum(len(b.data) for b in mesh.cells if b.type == "triangle")
    assert not any(b.type == "tetra" for b in mesh.cells)
    _assert_closed_and_oriented(tris)
    pts = mesh.points
    if volume is None:                                # wedge with the default shape parameters
        b, L, D, f = 1.0, 3.0, 1.0, 0.5
        tf, cs = math.tan(math.radians(30)), 1 / math.tan(math.radians(25))
        volume = quad(lambda z: (b + z * tf) * (L + z * cs), -D, f)[0]
        tol = 1e-3                                    # flat faces and gently curved ruled sides
    else:
        tol = 0.03                                    # chordal error of the faceted curved surfaces
        centre = np.array([params.get(f"center_{k}", 0.0) for k in "xyz"])
        assert _divergence_volume(pts - centre, tris) == pytest.approx(volume, rel=tol)
        assert 0.5 * np.linalg.norm(_tri_normals(pts, tris), axis=1).sum() == pytest.approx(area, rel=tol)
    assert _divergence_volume(pts, tris) == pytest.approx(volume, rel=tol)
    assert report.dim == 2 and report.total_volume > 0


def test_indenter_parameter_checks(tmp_path):
    """Parameters of another shape, unknown shapes and impossible wedges are refused, named."""
    cases = [
        (dict(shape="sphere", length=2.0), "length"),
        (dict(shape="cone"), "shape"),
        (dict(shape="cylinder", axis="w"), "axis"),
        (dict(shape="wedge", stem_angle=0.2), "stem_angle"),      # stem reaches the aft end too high
        (dict(shape="wedge", flare_angle=1.2), "flare_angle"),    # sides cross above the bottom
        (dict(shape="sphere", radius=0.0), "radius"),
    ]
    for bad, param in cases:
        with pytest.raises(ModelParameterError) as info:
            indenters.build(tmp_path / "x.msh", **bad)
        assert info.value.param == param, bad


# ------------------------------------------------------------------------------------- meshing API

def test_resolve_model_by_name_and_errors(tmp_path):
    """Names resolve to pdfem.models modules; unknown names list the available models."""
    assert resolve_model("hull_panel") is hull_panel
    with pytest.raises(ModelParameterError) as info:
        resolve_model("hull_pannel")
    msg = str(info.value)
    for name in ("hull_panel", "propeller_blade", "indenters"):
        assert name in msg
    with pytest.raises(ModelParameterError, match="no such model file"):
        resolve_model(str(tmp_path / "missing.py"))
    (tmp_path / "nobuild.py").write_text("PARAMETERS = {}\n")
    with pytest.raises(ModelParameterError, match="build"):
        resolve_model(str(tmp_path / "nobuild.py"))


_USER_MODEL = '''
"""A user's model script: a box of tetrahedra."""
from pdfem.meshing import check_parameters, finish_mesh, gmsh_session

PARAMETERS = {"side": (1.0, "m", "box side"), "element_size": (0.5, "m", "mesh size")}

def build(path, **params):
    p = check_parameters(PARAMETERS, params)
    with gmsh_session("box") as gmsh:
        v = gmsh.model.occ.addBox(0, 0, 0, p["side"], p["side"], p["side"])
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [v], name="solid")
        gmsh.option.setNumber("Mesh.MeshSizeMax", p["element_size"])
        gmsh.model.mesh.generate(3)
        return finish_mesh(path, "box", p, dim=3)
'''


def test_mesh_model_from_a_path_with_set_strings(tmp_path, monkeypatch):
    """A .py path is imported and run; --set strings take the defaults' types; the default output
    is <model>.msh in the working directory. Reference: the box volume side^3."""
    script = tmp_path / "my_box.py"
    script.write_text(_USER_MODEL)
    monkeypatch.chdir(tmp_path)
    report = mesh_model(str(script), parse_set(["side=0.5", "element_size = 0.2"]), None)
    assert report.path == tmp_path / "my_box.msh"
    assert (tmp_path / "my_box.msh").exists()
    assert report.total_volume == pytest.approx(0.125, rel=1e-12)
    assert report.groups == {"solid": 3}


def test_mesh_model_by_name_and_set_errors(tmp_path):
    """--set: unknown keys list the valid ones; unparsable values and missing '=' name the key."""
    out = tmp_path / "sub" / "cyl.msh"
    report = mesh_model("indenters", {"shape": "cylinder", "radius": "0.2", "length": "0.5",
                                      "element_size": "0.1"}, out)
    assert report.path == out and out.exists()
    assert report.parameters["radius"] == 0.2 and report.parameters["axis"] == "z"
    assert "contact (2-D)" in report.text()

    with pytest.raises(ModelParameterError) as info:
        mesh_model("hull_panel", {"thickness": "0.02"}, tmp_path / "x.msh")
    assert info.value.param == "thickness"
    for key in hull_panel.PARAMETERS:
        assert key in str(info.value)
    with pytest.raises(ModelParameterError) as info:
        mesh_model("hull_panel", {"length": "two"}, tmp_path / "x.msh")
    assert info.value.param == "length"
    with pytest.raises(ModelParameterError):
        parse_set(["length"])
    assert coerce_parameters({"flag": (False, "-", ""), "n": (3, "-", "")}, {"flag": "yes", "n": "7"}) == \
        {"flag": True, "n": 7}
    # the command line maps these to exit status 2
    assert issubclass(ModelParameterError, InputError) and issubclass(ModelParameterError, ValueError)


def _discrete_mesh(gmsh, nodes: np.ndarray, elements: np.ndarray, dim: int, group: str) -> None:
    tag = gmsh.model.addDiscreteEntity(dim)
    gmsh.model.mesh.addNodes(dim, tag, list(range(1, len(nodes) + 1)), nodes.ravel().tolist())
    etype = 4 if dim == 3 else 2
    gmsh.model.mesh.addElementsByType(tag, etype, [], (elements + 1).ravel().tolist())
    gmsh.model.addPhysicalGroup(dim, [tag], name=group)


_TET = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)


@pytest.mark.parametrize("nodes, cells, dim, closed, match", [
    (_TET, np.array([[0, 2, 1, 3]]), 3, False, "inverted"),                        # left-handed tet
    (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float), np.array([[0, 1, 2, 3]]), 3, False,
     "inverted or zero-volume"),                                                   # flat tet
    (_TET, np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2]]), 2, True, "not closed"),   # a tet missing a face
    (np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]], float), np.array([[0, 1, 2], [0, 1, 3]]), 2, False,
     "zero-volume"),                                                               # collinear triangle
])
def test_finish_mesh_refuses_bad_meshes(tmp_path, nodes, cells, dim, closed, match):
    """Inverted, zero-volume and open meshes are refused and no file is written."""
    out = tmp_path / "bad.msh"
    with gmsh_session("bad") as gmsh:
        _discrete_mesh(gmsh, nodes, cells, dim, "g")
        with pytest.raises(MeshQualityError, match=match):
            finish_mesh(out, "bad", {}, dim=dim, closed_surface=closed)
    assert not out.exists()


def test_finish_mesh_orients_a_closed_surface(tmp_path):
    """A tetrahedron's surface given with one face reversed comes out closed, consistent and
    outward. Reference: the unit corner tetrahedron's volume 1/6."""
    faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 3, 2]])   # last face points inward
    with gmsh_session("tetsurf") as gmsh:
        tags = [gmsh.model.addDiscreteEntity(2) for _ in faces]
        gmsh.model.mesh.addNodes(2, tags[0], [1, 2, 3, 4], _TET.ravel().tolist())
        for tag, f in zip(tags, faces):
            gmsh.model.mesh.addElementsByType(tag, 2, [], (f + 1).tolist())
        gmsh.model.addPhysicalGroup(2, tags, name="contact")
        report = finish_mesh(tmp_path / "t.msh", "t", {}, dim=2, closed_surface=True)
    mesh = meshio.read(tmp_path / "t.msh")
    tris = _cells(mesh, "contact", "triangle")
    _assert_closed_and_oriented(tris)
    assert _divergence_volume(mesh.points, tris) == pytest.approx(1 / 6, rel=1e-12)
    assert report.min_angle == pytest.approx(45.0)


def test_quality_measures_of_regular_elements():
    """Reference: a regular tetrahedron has dihedral angles arccos(1/3) = 70.53 deg and inradius
    a / (2 sqrt 6); an equilateral triangle has 60 deg angles."""
    p = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float)   # edge 2 sqrt 2
    t = np.array([[0, 1, 2, 3]])
    if _tet_volumes(p, t)[0] < 0:
        t = t[:, [0, 2, 1, 3]]
    assert tet_min_dihedral(p, t)[0] == pytest.approx(math.degrees(math.acos(1 / 3)))
    assert tet_inradii(p, t)[0] == pytest.approx(2 * math.sqrt(2) / (2 * math.sqrt(6)))
    tri = np.array([[0, 0, 0], [1, 0, 0], [0.5, math.sqrt(3) / 2, 0]])
    assert triangle_min_angle(tri, np.array([[0, 1, 2]]))[0] == pytest.approx(60.0)


def test_gmsh_session_is_finalised_after_an_error():
    """The session context always finalises gmsh, also when the body raises."""
    import gmsh

    with pytest.raises(ZeroDivisionError):
        with gmsh_session("boom"):
            1 / 0
    assert not gmsh.isInitialized()
