"""Geometric regions: point membership against analytic inside tests.

References: the analytic predicates of a box, a cylinder (axial and radial coordinates) and a
sphere; for closed triangle meshes (written by gmsh) the analytic solid they approximate, tested
only on points farther from its surface than the mesh's chord error.
"""

from __future__ import annotations

import numpy as np
import pytest

from pdfem.geometry.shapes import Box, ClosedSurface, Cylinder, Sphere

RNG = np.random.default_rng(20240611)


# -- analytic shapes ----------------------------------------------------------------------------

def test_box_contains_matches_analytic_predicate():
    """Random points against lo <= x <= hi; faces, edges and corners are inside."""
    box = Box((-1.0, 0.0, 2.0), (3.0, 0.5, 2.25))
    lo, hi = box.bounds()
    assert lo.tolist() == [-1.0, 0.0, 2.0] and hi.tolist() == [3.0, 0.5, 2.25]
    x = RNG.uniform(lo - 0.5, hi + 0.5, size=(20000, 3))
    assert np.array_equal(box.contains(x), np.all((x >= lo) & (x <= hi), axis=1))
    on_faces = np.array([[-1.0, 0.25, 2.1], [3.0, 0.5, 2.25], [0.0, 0.0, 2.0], [1.0, 0.3, 2.25]])
    assert box.contains(on_faces).all()
    diag = np.linalg.norm(hi - lo)
    just_out = np.array([[3.0 + 1e-7 * diag, 0.2, 2.1], [0.0, -1e-7 * diag, 2.1]])
    assert not box.contains(just_out).any()
    assert box.contains(np.array([[3.0 + 1e-10 * diag, 0.2, 2.1]])).all()  # inside the tolerance


def test_cylinder_contains_matches_analytic_predicate():
    """A tilted cylinder: 0 <= (x-b).a <= L and |(x-b) - ((x-b).a) a| <= r."""
    base = np.array([0.3, -0.2, 1.0])
    axis = np.array([1.0, 2.0, -0.5])
    cyl = Cylinder(tuple(base), tuple(axis * 3.0), 0.4, 2.0)  # axis length does not matter
    a = axis / np.linalg.norm(axis)
    lo, hi = cyl.bounds()
    x = RNG.uniform(lo - 0.2, hi + 0.2, size=(30000, 3))
    d = x - base
    s = d @ a
    radial = np.linalg.norm(d - s[:, None] * a, axis=1)
    ref = (s >= 0) & (s <= 2.0) & (radial <= 0.4)
    got = cyl.contains(x)
    assert np.array_equal(got, ref)
    assert ref.sum() > 1000
    # the bounding box is tight: the inside points reach it within a few per cent of r
    inside = x[ref]
    assert np.all(inside >= lo) and np.all(inside <= hi)
    assert np.all(inside.min(axis=0) - lo < 0.1) and np.all(hi - inside.max(axis=0) < 0.1)


def test_axis_aligned_cylinder_bounds_and_surface():
    """Axis along z: bounds base +- r in x, y and base .. base + L in z; the surface is inside."""
    cyl = Cylinder((1.0, 2.0, 3.0), (0.0, 0.0, 1.0), 0.5, 4.0)
    lo, hi = cyl.bounds()
    np.testing.assert_allclose(lo, [0.5, 1.5, 3.0])
    np.testing.assert_allclose(hi, [1.5, 2.5, 7.0])
    surface = np.array([[1.5, 2.0, 5.0], [1.0, 2.0, 3.0], [1.0, 2.0, 7.0], [1.0, 1.5, 7.0]])
    assert cyl.contains(surface).all()
    assert not cyl.contains(np.array([[1.0, 2.0, 7.0 + 1e-6], [1.0, 2.5 + 1e-6, 4.0]])).any()


def test_sphere_contains_matches_analytic_predicate():
    """Random points against |x - c| <= r."""
    sph = Sphere((1.0, -2.0, 0.5), 0.75)
    lo, hi = sph.bounds()
    np.testing.assert_allclose(lo, [0.25, -2.75, -0.25])
    np.testing.assert_allclose(hi, [1.75, -1.25, 1.25])
    x = RNG.uniform(lo - 0.1, hi + 0.1, size=(20000, 3))
    ref = np.linalg.norm(x - [1.0, -2.0, 0.5], axis=1) <= 0.75
    assert np.array_equal(sph.contains(x), ref)
    assert sph.contains(np.array([[1.75, -2.0, 0.5]])).all()


@pytest.mark.parametrize("make", [
    lambda: Box((0, 0, 0), (1, 0, 1)),
    lambda: Box((0, 0, 0), (1, 1, -1)),
    lambda: Box((0, 0), (1, 1)),
    lambda: Box((0, 0, float("nan")), (1, 1, 1)),
    lambda: Cylinder((0, 0, 0), (0, 0, 0), 1.0, 1.0),
    lambda: Cylinder((0, 0, 0), (0, 0, 1), 0.0, 1.0),
    lambda: Cylinder((0, 0, 0), (0, 0, 1), 1.0, -2.0),
    lambda: Sphere((0, 0, 0), -1.0),
    lambda: Sphere((0, 0, 0), float("inf")),
])
def test_bad_parameters_raise_value_error(make):
    """Degenerate or malformed shapes are refused with a ValueError."""
    with pytest.raises(ValueError):
        make()


def test_bad_parameter_messages_say_what_is_wrong():
    """The messages name the parameter."""
    with pytest.raises(ValueError, match="max must be larger than its min"):
        Box((0, 0, 0), (1, 0, 1))
    with pytest.raises(ValueError, match="axis must not be the zero vector"):
        Cylinder((0, 0, 0), (0, 0, 0), 1.0, 1.0)
    with pytest.raises(ValueError, match="radius"):
        Sphere((0, 0, 0), 0.0)


# -- closed triangle meshes -------------------------------------------------------------------

def _unit_cube_surface(flip_some: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The unit cube as 12 triangles, each face split along the diagonal through its (0,0) corner."""
    v = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tri = []
    for a, b, c, d in quads:
        tri += [(a, b, c), (a, c, d)]
    tri = np.array(tri, dtype=np.int32)
    if flip_some:
        tri[::3] = tri[::3, ::-1]
    return v, tri


@pytest.mark.parametrize("flip_some", [False, True])
def test_cube_mesh_with_rays_through_edges_and_vertices(flip_some):
    """Lattice points whose vertical rays hit mesh edges and vertices exactly (0 < x, y < 1 on the
    face diagonals, x or y on the cube's walls excluded) are classified like the analytic cube;
    the triangles' orientation does not matter."""
    surf = ClosedSurface(*_unit_cube_surface(flip_some))
    g = np.linspace(-0.5, 1.5, 17)
    x = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    on_surface = np.all((x >= 0) & (x <= 1), axis=1) & np.any((x == 0) | (x == 1), axis=1)
    inside = np.all((x > 0) & (x < 1), axis=1)
    got = surf.contains(x)
    assert np.array_equal(got[~on_surface], inside[~on_surface])
    diag = x[(x[:, 0] == x[:, 1]) & inside]
    assert diag.shape[0] > 0 and surf.contains(diag).all()


def _gridded_cube_surface(side: float, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Closed surface of [0, side]^3, each face a k x k grid of squares split along alternating
    diagonals: interior face vertices have fans of 4 to 8 triangles."""
    g = np.arange(k + 1) * (side / k)
    index: dict = {}
    tris = []
    for axis in range(3):
        u, w = [a for a in range(3) if a != axis]
        for level in (g[0], g[-1]):
            def vid(i, j):
                p = [0.0, 0.0, 0.0]
                p[axis], p[u], p[w] = level, g[i], g[j]
                return index.setdefault(tuple(p), len(index))
            for i in range(k):
                for j in range(k):
                    q = (vid(i, j), vid(i + 1, j), vid(i + 1, j + 1), vid(i, j + 1))
                    if (i + j) % 2:
                        tris += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
                    else:
                        tris += [(q[0], q[1], q[3]), (q[1], q[2], q[3])]
    return np.array(list(index)), np.array(tris, dtype=np.int32)


@pytest.mark.parametrize("side, k, angle", [(0.7, 14, 0.0), (0.7, 14, 0.3), (3.3, 22, 0.3)])
def test_rays_a_few_ulps_from_vertices(side, k, angle):
    """Points at mid-height whose vertical ray passes 0-3 ulps from an interior vertex of the top
    and bottom faces (the fans meet there) are all inside the (rotated) cube."""
    v, t = _gridded_cube_surface(side, k)
    rot = np.array([[np.cos(angle), -np.sin(angle), 0.0], [np.sin(angle), np.cos(angle), 0.0], [0, 0, 1]])
    surf = ClosedSurface(v @ rot.T, t)
    top = v[(v[:, 2] == v[:, 2].max()) & np.all((v[:, :2] > 0) & (v[:, :2] < v[:, 0].max()), axis=1)] @ rot.T
    steps = np.array([-3, -1, 0, 1, 3])
    du, dv = np.meshgrid(steps, steps, indexing="ij")
    px = (top[:, 0, None] + du.ravel() * np.spacing(top[:, 0, None]))
    py = (top[:, 1, None] + dv.ravel() * np.spacing(top[:, 1, None]))
    x = np.stack([px.ravel(), py.ravel(), np.full(px.size, 0.5 * v[:, 2].max())], axis=1)
    assert surf.contains(x).all()


def test_open_surface_raises():
    """A cube with one triangle removed has 3 open edges."""
    v, t = _unit_cube_surface()
    with pytest.raises(ValueError, match="the surface has 3 open edges; a closed surface is needed"):
        ClosedSurface(v, t[1:])


def test_duplicate_vertices_are_merged():
    """A triangle soup (every triangle with its own vertices, as in STL) is closed once merged."""
    v, t = _unit_cube_surface()
    soup = v[t.ravel()]
    surf = ClosedSurface(soup, np.arange(soup.shape[0], dtype=np.int32).reshape(-1, 3))
    assert surf.vertices.shape == (8, 3) and surf.triangles.shape == (12, 3)
    assert surf.contains(np.array([[0.3, 0.6, 0.2]])).all()


def _gmsh_write(path, build):
    """Build a gmsh model with ``build(gmsh)``, mesh it and write it to ``path``."""
    gmsh = pytest.importorskip("gmsh")
    owner = not gmsh.isInitialized()
    if owner:
        gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add(path.stem)
        build(gmsh)
        gmsh.write(str(path))
        gmsh.model.remove()
    finally:
        if owner:
            gmsh.finalize()
    return path


def _sphere_model(gmsh, radius=1.0, size=0.15):
    gmsh.model.occ.addSphere(0.0, 0.0, 0.0, radius)
    gmsh.model.occ.synchronize()
    surfaces = [tag for _, tag in gmsh.model.getEntities(2)]
    gmsh.model.addPhysicalGroup(2, surfaces, name="skin")
    gmsh.model.addPhysicalGroup(3, [tag for _, tag in gmsh.model.getEntities(3)], name="ice")
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.model.mesh.generate(3)


@pytest.fixture(scope="module")
def sphere_msh(tmp_path_factory):
    return _gmsh_write(tmp_path_factory.mktemp("mesh") / "sphere.msh", _sphere_model)


def test_gmsh_sphere_surface_group_vs_analytic_sphere(sphere_msh):
    """Surface of the named group 'skin' vs |x| < 1, on points farther than 0.05 from the sphere
    (the chord error of a mesh of size 0.15 on radius 1 is about 0.15**2 / 8 = 0.003)."""
    surf = ClosedSurface.from_file(sphere_msh, group="skin")
    lo, hi = surf.bounds()
    np.testing.assert_allclose(lo, -1.0, atol=0.01)
    np.testing.assert_allclose(hi, 1.0, atol=0.01)
    x = RNG.uniform(-1.3, 1.3, size=(40000, 3))
    r = np.linalg.norm(x, axis=1)
    clear = np.abs(r - 1.0) > 0.05
    got = surf.contains(x)
    assert np.array_equal(got[clear], r[clear] < 1.0)


def test_gmsh_tetra_volume_boundary_equals_surface(sphere_msh):
    """The boundary faces of the tetrahedra of group 'ice' enclose the same points as 'skin'."""
    skin = ClosedSurface.from_file(sphere_msh, group="skin")
    vol = ClosedSurface.from_file(sphere_msh, group="ice")
    assert vol.triangles.shape == skin.triangles.shape
    x = RNG.uniform(-1.2, 1.2, size=(20000, 3))
    assert np.array_equal(vol.contains(x), skin.contains(x))


def test_gmsh_unknown_group_lists_the_groups(sphere_msh):
    """A missing physical group is a ValueError naming the groups the file has."""
    with pytest.raises(ValueError, match="no physical group named 'hull'.*ice, skin"):
        ClosedSurface.from_file(sphere_msh, group="hull")


def _torus_model(gmsh):
    gmsh.model.occ.addTorus(0.0, 0.0, 0.0, 1.0, 0.35)
    gmsh.model.occ.synchronize()
    gmsh.model.addPhysicalGroup(2, [tag for _, tag in gmsh.model.getEntities(2)], name="skin")
    gmsh.option.setNumber("Mesh.MeshSizeMax", 0.08)
    gmsh.model.mesh.generate(2)


def test_gmsh_torus_stl_vs_analytic_torus(tmp_path):
    """A non-convex solid read from STL: (sqrt(x^2 + y^2) - 1)^2 + z^2 < 0.35^2, margin 0.03
    (chord error about 0.08**2 / (8 * 0.35) = 0.002)."""
    path = _gmsh_write(tmp_path / "torus.stl", _torus_model)
    surf = ClosedSurface.from_file(path)
    x = RNG.uniform([-1.5, -1.5, -0.5], [1.5, 1.5, 0.5], size=(40000, 3))
    dist = np.hypot(np.hypot(x[:, 0], x[:, 1]) - 1.0, x[:, 2])
    clear = np.abs(dist - 0.35) > 0.03
    got = surf.contains(x)
    assert np.array_equal(got[clear], dist[clear] < 0.35)
    assert not surf.contains(np.array([[0.0, 0.0, 0.0]])).any()  # the hole


def test_gmsh_open_surface_file_raises(tmp_path):
    """A single disc (an open surface) read from a .msh is refused with the open-edge message."""
    def disc(gmsh):
        gmsh.model.occ.addDisk(0, 0, 0, 1.0, 1.0)
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(2, [1], name="lid")
        gmsh.option.setNumber("Mesh.MeshSizeMax", 0.3)
        gmsh.model.mesh.generate(2)

    path = _gmsh_write(tmp_path / "disc.msh", disc)
    with pytest.raises(ValueError, match=r"the surface has \d+ open edges; a closed surface is needed"):
        ClosedSurface.from_file(path, group="lid")
