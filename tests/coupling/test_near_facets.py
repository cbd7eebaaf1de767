"""The part of a contact surface near the ice (:mod:`pdfem.coupling.near_facets`) and the
pseudo-normals of a part (:func:`pdfem.coupling.facets.pseudo_normals_of`).

References: the definition of the angle-weighted pseudo-normal (Baerentzen & Aanaes, IEEE TVCG
11, 2005: a vertex's normal is the sum of the incident faces' normals weighted by the face's
angle at the vertex; an edge's the sum of its two faces' normals), computed face by face in
numpy; the whole surface's pass, whose numbers a part's must equal bit for bit; a brute-force
distance from every particle to every facet's grown box; the analytic contact of a flat plate
(a particle is in contact when it lies behind the plate's interior within the search radius).
"""

from __future__ import annotations

import numpy as np

from pdfem.coupling.contact import SurfaceContact
from pdfem.coupling.facets import FacetTopology, pseudo_normals, pseudo_normals_of
from pdfem.coupling.near_facets import NearFacets
from pdfem.fem.step_compliance import LumpedCompliance


def _sheet(n: int, size: float, wave: float, seed: int = 0):
    """A wavy n x n square sheet of side ``size`` (m) in two triangles per square (diagonals
    alternating), normals up: (points, triangles)."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.linspace(0.0, size, n + 1), np.linspace(0.0, size, n + 1),
                       indexing="ij")
    z = wave * np.sin(3.0 * x) * np.cos(2.0 * y) + 1e-3 * wave * rng.standard_normal(x.shape)
    points = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    tri = []
    for i in range(n):
        for j in range(n):
            a, b, c, d = i * (n + 1) + j, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1, \
                i * (n + 1) + j + 1
            tri += [[a, b, c], [a, c, d]] if (i + j) % 2 else [[a, b, d], [b, c, d]]
    return points, np.array(tri, dtype=np.int32)


def _reference_normals(points, tri, n_edges, tri_edges):
    """Face, edge and vertex pseudo-normals by their definition, in numpy (float64)."""
    x = points[tri]
    face = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    face /= np.linalg.norm(face, axis=1)[:, None]
    edge = np.zeros((n_edges, 3))
    vertex = np.zeros((len(points), 3))
    for t in range(len(tri)):
        for k in range(3):
            edge[tri_edges[t, k]] += face[t]
            q = x[t, (k + 1) % 3] - x[t, k]
            r = x[t, (k + 2) % 3] - x[t, k]
            angle = np.arccos(np.dot(q, r) / (np.linalg.norm(q) * np.linalg.norm(r)))
            vertex[tri[t, k]] += angle * face[t]
    edge /= np.linalg.norm(edge, axis=1)[:, None]
    vertex /= np.linalg.norm(vertex, axis=1)[:, None]
    return face, edge, vertex


def test_pseudo_normals_of_the_near_part_are_the_whole_surfaces_bit_for_bit():
    """Ice over one corner of a wavy sheet of 1,800 facets: the near facets are a small part of
    the sheet, and the normals of their faces, edges and vertices computed over the part alone
    are the whole surface's, bit for bit; the whole surface's agree with the definition."""
    points, tri = _sheet(30, 3.0, 0.1)
    topo = FacetTopology.from_triangles(tri, len(points))
    whole = pseudo_normals(points, topo)
    reference = _reference_normals(points, tri, topo.n_edges, topo.tri_edges)
    for got, ref in zip(whole, reference):
        np.testing.assert_allclose(got, ref, rtol=0.0, atol=1e-12)
    rng = np.random.default_rng(1)
    y = np.column_stack([rng.uniform(0.2, 0.6, 300), rng.uniform(0.3, 0.8, 300),
                         rng.uniform(0.0, 0.3, 300)])
    near = NearFacets(topo, len(points), reach=0.05, skin=0.05)
    near.build(points, y)
    assert 0 < len(near.facets) < 0.15 * len(tri)
    assert len(near.part.triangles) > len(near.facets)        # the ring around them
    part = tuple(np.full_like(a, np.nan) for a in whole)
    pseudo_normals_of(points, topo, near.part, part)
    f = near.facets
    for rows, k in ((f, 0), (np.unique(topo.tri_edges[f]), 1), (np.unique(tri[f]), 2)):
        assert np.array_equal(part[k][rows], whole[k][rows])
    # without the ring the vertices' and edges' sums miss facets: other numbers
    alone = tuple(np.full_like(a, np.nan) for a in whole)
    core = near.part._replace(triangles=f)
    pseudo_normals_of(points, topo, core, alone)
    assert not np.array_equal(alone[2][np.unique(tri[f])], whole[2][np.unique(tri[f])])


def test_near_facets_hold_every_facet_within_reach_and_two_skins():
    """Every facet whose bounding box lies within reach + 2 skin of a particle (brute force over
    all pairs) is near; particles spread in three clusters over a larger sheet."""
    points, tri = _sheet(40, 4.0, 0.2, seed=2)
    topo = FacetTopology.from_triangles(tri, len(points))
    rng = np.random.default_rng(5)
    y = np.concatenate([c + rng.uniform(-0.2, 0.2, (100, 3))
                        for c in ([0.5, 0.5, 0.1], [3.0, 1.0, -0.2], [2.0, 3.5, 0.3])])
    reach, skin = 0.04, 0.03
    near = NearFacets(topo, len(points), reach, skin)
    near.build(points, y)
    x = points[tri]
    lo, hi = x.min(axis=1), x.max(axis=1)
    gap = np.maximum(0.0, np.maximum(lo[None] - y[:, None], y[:, None] - hi[None]))
    within = (np.linalg.norm(gap, axis=2) <= reach + 2 * skin).any(axis=0)
    assert within.sum() > 20
    assert set(np.flatnonzero(within)) <= set(near.facets.tolist())
    assert len(near.facets) < 0.2 * len(tri)


class _Sheet:
    """A sheet of nodes ``points`` and ``surface_triangles`` (m), lifted by ``z`` (m), at rest
    (a ContactSurface); the tests move it by ``z`` or by its ``points``."""

    def __init__(self, points: np.ndarray, triangles: np.ndarray) -> None:
        self.points, self.surface_triangles = points, triangles
        self.z = 0.0

    def surface_points(self):
        return self.points + [0.0, 0.0, self.z]

    def surface_velocities(self):
        return np.zeros_like(self.points)

    def surface_compliance(self):
        return LumpedCompliance(np.zeros_like(self.points))

    def surface_rotation(self):
        return None


def _flat_sheet(n: int = 20) -> _Sheet:
    """A flat n x n sheet on [0, 2] x [0, 2] at height 0, normal +z."""
    points, triangles = _sheet(n, 2.0, 0.0)
    return _Sheet(points * [1.0, 1.0, 0.0], triangles)


def _resolve(contact, sheet, y):
    """The rows the contact gives an impulse, the sheet where it is now (particles moving
    down, 1 mm in the step)."""
    contact.set_surface(sheet.surface_points(), sheet.surface_velocities())
    v = np.tile([0.0, 0.0, -1.0], (len(y), 1))
    return contact.resolve(y.copy(), y - 0.001 * v, v, np.ones(len(y)), 0.001).rows


def _lone_case(anchor: float):
    """A sheet, ice over one corner, a particle deep below at ``anchor`` (m: where the cells of
    the particles start) and a lone particle under the opposite corner, out of reach by 1.9
    skins: (sheet, contact, particles, reach = skin)."""
    reach = 0.02
    sheet = _flat_sheet()
    rng = np.random.default_rng(7)
    ice = np.column_stack([rng.uniform(0.1, 0.4, 200), rng.uniform(0.1, 0.4, 200),
                           rng.uniform(0.05, 0.3, 200)])
    y = np.concatenate([ice, [[0.3, 1.7, anchor]], [[1.73, 1.61, -(reach + 1.9 * reach)]]])
    return sheet, SurfaceContact(sheet, search_radius=reach), y, reach


def test_a_lone_particle_far_from_the_ice_finds_its_facet_after_small_and_large_moves():
    """The lone particle of :func:`_lone_case`: the sheet comes down and the particle up by
    0.98 skin each: neither moved a skin, the selection is kept, and the particle, now just
    within the search radius behind the sheet's interior, is in contact (the analytic contact,
    and a contact made afresh), wherever the particles' cells start. Then both move 3 skins
    the other way: made again, out of contact; and 3 skins back, just within reach: made
    again, in contact again."""
    lone = 201
    for anchor in np.linspace(-1.0, -0.9, 12):
        sheet, contact, y, skin = _lone_case(anchor)
        reach = skin
        assert len(_resolve(contact, sheet, y)) == 0
        builds = contact.near.builds
        assert len(contact.near.facets) < 0.2 * len(sheet.surface_triangles)
        sheet.z -= 0.98 * skin
        y[lone, 2] += 0.98 * skin
        rows = _resolve(contact, sheet, y)
        assert contact.near.builds == builds                         # kept
        assert -reach < y[lone, 2] - sheet.z < 0.0                    # analytic: in contact
        assert rows.tolist() == [lone]
        fresh = SurfaceContact(sheet, search_radius=reach)
        assert _resolve(fresh, sheet, y).tolist() == [lone]
    sheet.z += 3.0 * skin
    y[lone, 2] -= 3.0 * skin
    assert len(_resolve(contact, sheet, y)) == 0
    assert contact.near.builds > builds                              # made again
    builds = contact.near.builds
    sheet.z -= 3.0 * skin
    y[lone, 2] += 2.99 * skin
    rows = _resolve(contact, sheet, y)
    assert contact.near.builds > builds
    assert -reach < y[lone, 2] - sheet.z < 0.0
    assert rows.tolist() == [lone]


def test_the_contacts_normals_of_the_near_part_are_the_whole_surfaces_as_it_moves():
    """A contact over a deforming sheet: after each substep the pseudo-normals it uses on the
    near part (near facets, their edges and vertices) are the whole surface's, bit for bit, at
    the positions of the last update with normals; also when the sheet moves three skins
    within a coupling step (``normals=False``: the normals of the step's start) and the
    selection is made again."""
    sheet = _Sheet(*_sheet(30, 3.0, 0.1, seed=4))   # wavy
    topo = FacetTopology.from_triangles(sheet.surface_triangles, len(sheet.points))
    rng = np.random.default_rng(11)
    y = np.column_stack([rng.uniform(1.0, 1.5, 400), rng.uniform(1.2, 1.6, 400),
                         rng.uniform(0.12, 0.4, 400)])
    contact = SurfaceContact(sheet, search_radius=0.03)
    v = np.zeros_like(y)

    def near_rows_equal(points):
        whole = pseudo_normals(points, topo)
        f = contact.near.facets
        rows = (f, np.unique(topo.tri_edges[f]), np.unique(sheet.surface_triangles[f]))
        return all(np.array_equal(contact.pseudo_normals[k][r], whole[k][r])
                   for k, r in enumerate(rows))

    for step in range(4):
        sheet.points = sheet.points + rng.normal(0.0, 2e-3, sheet.points.shape)
        start = sheet.surface_points()
        contact.set_surface(start, sheet.surface_velocities())
        contact.resolve(y, y.copy(), v, np.ones(len(y)), 1e-3)
        assert 0 < len(contact.near.facets) < 0.2 * len(sheet.surface_triangles)
        assert near_rows_equal(start)
        builds, facets = contact.near.builds, contact.near.facets
        sheet.points = sheet.points + [0.09, 0.0, 0.0] + rng.normal(0.0, 2e-3, start.shape)
        contact.set_surface(sheet.surface_points(), sheet.surface_velocities(), normals=False)
        contact.resolve(y, y.copy(), v, np.ones(len(y)), 1e-3)
        assert contact.near.builds > builds and not np.array_equal(contact.near.facets, facets)
        assert near_rows_equal(start)
        assert not near_rows_equal(sheet.surface_points())      # (those of its start)
