"""Surface-element contact between ice particles and a structure (seed paper, Eqs. 5-8, with
the structure's inertia).

After each position update of the ice, :meth:`SurfaceContact.resolve` finds the particles that
have crossed the structure's contact surface, moves each back onto the surface (the closest
point of the surface: the seed paper's "newly allocated" position) and gives the particle and
the surface point it hit equal and opposite impulses, at the same instant, with the surface
position and velocity of that instant:

* the impulse stops the normal relative velocity (perfectly plastic, as Eq. 5 of the seed
  paper: the particle leaves with the surface's normal velocity), computed with the masses of
  BOTH sides, ``j_n = -v_n / (1/m + 1/M_s)``, ``1/M_s`` the inverse mass of the surface point
  from the lumped masses of the facet's nodes (zero for a rigid or supported surface, which
  recovers Eq. 5 exactly);
* optional Coulomb friction takes off tangential relative velocity, at most ``friction x j_n``;
* the opposite impulse goes to the facet's three nodes by the barycentric weights of the
  contact point (Eqs. 7-8), so the impulse that leaves the ice equals the impulse that reaches
  the structure, exactly. The caller applies it to the structure as a velocity change at the
  same instant (:meth:`pdfem.fem.base.Structure.apply_surface_impulse`), or, for a structure
  advanced by implicit steps, as an amendment of the step just taken.

The surface's inverse mass is its compliance for the contact
(:meth:`pdfem.fem.base.Structure.surface_compliance`, 1/kg): how far the surface point gives
way over the contact per unit impulse and time. For an explicit substep that is the lumped
``1/M`` of the nodes; for an implicit step it is the step's mean response ``A^-1 / 2``, which
couples neighbouring nodes (:mod:`pdfem.fem.step_compliance`): the contact then takes, for
every node, its response to the step's whole pattern of contacts, ``S_i = sum_k C_ik s_k``
with ``s_k`` the contacts' summed weights at node ``k`` (the share below), in world axes as a
3 x 3 block.

Why the structure's mass matters: with the structure taking the particle's impulse only later
(the seed paper's load held over the next step) a node lighter than the ice that rides on it
feels that ice's inertia one step late; the delayed feedback grows by the mass ratio every
step, so smaller steps make it worse (energy creation, then blow-up). Taking both masses in the
same instant makes every contact a plastic collision, which can only dissipate energy.

All contacts of one step see the surface velocities before that step's contacts, and a node's
mass is split among the contacts touching it in proportion to their barycentric weights
(an implicit step's node: the contacts near it too, by the coupling ``C_ik``), so
the impulses do not depend on the order of the particles or on how they are split over MPI
ranks, and several particles hitting one light node stop together as one plastic collision
(by convexity of the kinetic energy the step dissipates at least the sum of what each contact
would). A particle counts as inside when the closest surface point lies within the search
radius and the particle is behind it according to the angle-weighted pseudo-normal of the
feature (face, edge or vertex) the point lies on (:mod:`pdfem.coupling.facets`), which decides
the side correctly at edges and vertices. On an open surface (e.g. the outer face of a hull
panel) particles whose closest point is on the surface's rim are not in contact: they are
beside the surface, not behind it.

What a surface needs as it moves, its pseudo-normals and the grid of its facets, is made for
the part of it the particles can reach (:meth:`SurfaceContact.near_surface`,
:mod:`pdfem.coupling.near_facets`): the facets near the particles, kept until the surface or
the particles have moved a skin, and, for the normals of their edges and vertices, every facet
around them. A milling propeller's ice touches one blade; a hull's, a strip of it. The normals
of that part are the whole surface's, bit for bit, so the contacts are those of the whole
surface.

Units: m, s, kg, N s (impulses), J.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numba
import numpy as np
from numba import prange

from pdfem.coupling.broad_phase import Candidates
from pdfem.coupling.facet_grid import FacetGrid
from pdfem.coupling.facets import (FACE, FacetTopology, closest_point_on_triangle,
                                   pseudo_normals, pseudo_normals_of)
from pdfem.coupling.near_facets import NearFacets
from pdfem.coupling.nodal_impulse import ContactRecords
from pdfem.parallel.kernels import twin


class GridArrays(NamedTuple):
    """The facet grid's arrays (:class:`pdfem.coupling.facet_grid.FacetGrid`)."""

    cell_start: np.ndarray
    cell_facets: np.ndarray
    origin: np.ndarray
    inv_h: float
    dims: np.ndarray


class SurfaceArrays(NamedTuple):
    """A contact surface now: node positions ``pts`` (m), triangles, their edges, the face,
    edge and vertex pseudo-normals and the boundary flags (:mod:`pdfem.coupling.facets`)."""

    pts: np.ndarray
    tri: np.ndarray
    tri_edges: np.ndarray
    face_n: np.ndarray
    edge_n: np.ndarray
    vert_n: np.ndarray
    boundary_edge: np.ndarray
    boundary_node: np.ndarray


class SurfaceState(NamedTuple):
    """The surface's node positions now and at the drift's start (m), velocities (m/s),
    compliances (1/kg, (Ns, 3, 3) blocks in world axes), the contacts' share of each node (the
    factor on its block) and the triangles."""

    pts: np.ndarray
    pts0: np.ndarray
    vel: np.ndarray
    invm: np.ndarray
    share: np.ndarray
    tri: np.ndarray


class Drift(NamedTuple):
    """The particles' positions after and before the drift (m), their velocities (m/s) and
    masses (kg)."""

    y: np.ndarray
    y_old: np.ndarray
    v: np.ndarray
    mass: np.ndarray


@numba.njit(cache=True, inline="always")
def _box_distance2(p, a, b, c):
    """Squared distance (m^2) from ``p`` to the bounding box of the triangle ``a, b, c``."""
    d2 = 0.0
    for d in range(3):
        lo = min(a[d], min(b[d], c[d]))
        hi = max(a[d], max(b[d], c[d]))
        if p[d] < lo:
            d2 += (lo - p[d]) * (lo - p[d])
        elif p[d] > hi:
            d2 += (p[d] - hi) * (p[d] - hi)
    return d2


@twin(fastmath=False)
def _detect(y, rows, active, grid, surface, reach, facet, weight, normal):
    """For each particle ``rows[k]`` (if active): the facet it is behind (or -1), weights and
    contact normal, in entry k of ``facet``, ``weight``, ``normal`` (the tuples' arrays taken out
    before the ``prange``: numba loses writes through tuples there)."""
    cell_start, cell_facets, origin = grid.cell_start, grid.cell_facets, grid.origin
    inv_h, dims = grid.inv_h, grid.dims
    pts, tri, tri_edges = surface.pts, surface.tri, surface.tri_edges
    face_n, edge_n, vert_n = surface.face_n, surface.edge_n, surface.vert_n
    boundary_edge, boundary_node = surface.boundary_edge, surface.boundary_node
    nyz = dims[1] * dims[2]
    r2 = reach * reach
    for k in prange(rows.shape[0]):
        i = rows[k]
        facet[k] = -1
        if not active[i]:
            continue
        p = y[i]
        ci = int(np.floor((p[0] - origin[0]) * inv_h))
        cj = int(np.floor((p[1] - origin[1]) * inv_h))
        ck = int(np.floor((p[2] - origin[2]) * inv_h))
        if ci < 0 or cj < 0 or ck < 0 or ci >= dims[0] or cj >= dims[1] or ck >= dims[2]:
            continue
        c = ci * nyz + cj * dims[2] + ck
        best = -1
        best_d2 = r2
        bu = bv = bw = 0.0
        bfeat = 0
        for s in range(cell_start[c], cell_start[c + 1]):
            f = cell_facets[s]
            a = pts[tri[f, 0]]
            b = pts[tri[f, 1]]
            cc = pts[tri[f, 2]]
            # the closest point lies in the facet's bounding box: a facet whose box is
            # farther than the best so far can neither win nor tie (the same result, cheaper)
            if _box_distance2(p, a, b, cc) > best_d2:
                continue
            u, v, w, feat = closest_point_on_triangle(p, a, b, cc)
            d0 = p[0] - (u * a[0] + v * b[0] + w * cc[0])
            d1 = p[1] - (u * a[1] + v * b[1] + w * cc[1])
            d2 = p[2] - (u * a[2] + v * b[2] + w * cc[2])
            dd = d0 * d0 + d1 * d1 + d2 * d2
            if dd < best_d2 or (dd == best_d2 and best >= 0 and f < best):
                best, best_d2, bu, bv, bw, bfeat = f, dd, u, v, w, feat
        if best < 0:
            continue
        # pseudo-normal of the feature; rim features of an open surface are not contacts
        if bfeat == FACE:
            nx, ny, nz = face_n[best, 0], face_n[best, 1], face_n[best, 2]
        elif bfeat <= 3:
            node = tri[best, bfeat - 1]
            if boundary_node[node]:
                continue
            nx, ny, nz = vert_n[node, 0], vert_n[node, 1], vert_n[node, 2]
        else:
            e = tri_edges[best, bfeat - 4]
            if boundary_edge[e]:
                continue
            nx, ny, nz = edge_n[e, 0], edge_n[e, 1], edge_n[e, 2]
        a = pts[tri[best, 0]]
        b = pts[tri[best, 1]]
        cc = pts[tri[best, 2]]
        side = ((p[0] - (bu * a[0] + bv * b[0] + bw * cc[0])) * nx
                + (p[1] - (bu * a[1] + bv * b[1] + bw * cc[1])) * ny
                + (p[2] - (bu * a[2] + bv * b[2] + bw * cc[2])) * nz)
        if side < -1e-9 * reach:  # on the surface (to round-off) is not inside
            facet[k] = best
            weight[k, 0] = bu
            weight[k, 1] = bv
            weight[k, 2] = bw
            normal[k, 0] = nx
            normal[k, 1] = ny
            normal[k, 2] = nz


PARALLEL_CANDIDATES = 2_000
"""Candidates from which the narrow phase runs on numba's threads: below, one thread is faster
(the demo's 250 candidates: 114 us on one thread, 184 us on two)."""

SHARE_UNIT = 2.0 ** 40
"""Fixed-point unit of the contact weights summed per node: integer sums are exact, so the
shares are the same bit for bit whatever the order of the particles or their split over ranks."""


@numba.njit(cache=True)
def _shares(facet, weight, tri, share):
    """Add each contact's barycentric weights, in units of 1 / SHARE_UNIT, to ``share`` (int64,
    per surface node): how many contacts, weighted, a node's mass is split among this step."""
    for i in range(facet.shape[0]):
        f = facet[i]
        if f < 0:
            continue
        for k in range(3):
            share[tri[f, k]] += np.int64(np.rint(weight[i, k] * SHARE_UNIT))


@numba.njit(cache=True, inline="always")
def _quadratic(start, g, n):
    """``start + n . g . n`` for a symmetric (3, 3) ``g``: the diagonal terms first, in the
    order ``start + n0^2 g00 + n1^2 g11 + n2^2 g22``, then the others (zero for a diagonal
    ``g``: its sum keeps the bits of the diagonal form)."""
    out = start + n[0] ** 2 * g[0, 0] + n[1] ** 2 * g[1, 1] + n[2] ** 2 * g[2, 2]
    return out + 2.0 * (n[0] * n[1] * g[0, 1] + n[0] * n[2] * g[0, 2] + n[1] * n[2] * g[1, 2])


@numba.njit(cache=True)
def _respond(rows, facet, weight, ice, dt, surface, friction, particle_impulse, totals):
    """Give each contacting particle and the surface point it hit their impulse (Eq. 5 with the
    structure's inertia, module docstring); move the particle with its corrected velocity.

    Every contact uses the surface velocities ``vel`` as they were before the step's contacts,
    and a node's mass is split among the contacts touching it in proportion to their weights
    (``share``), so each particle's impulse does not depend on the order of the particles or
    on how they are split over MPI ranks. ``totals`` accumulates: [0:3] impulse to the
    structure (N s), [3] contacts; entry c of ``particle_impulse`` gets the impulse (N s) of
    particle ``rows[c]`` (entries without a contact are left alone); ``facet`` and ``weight`` are
    :func:`_detect`'s, entry c for particle ``rows[c]``. The structure's nodal share is summed
    apart, in global particle order (:mod:`pdfem.coupling.nodal_impulse`). ``ice``: a
    :class:`Drift`, ``surface``: a :class:`SurfaceState`.
    """
    y, y_old, v, mass = ice.y, ice.y_old, ice.v, ice.mass
    pts, pts0, vel, invm, share, tri = (surface.pts, surface.pts0, surface.vel, surface.invm,
                                        surface.share, surface.tri)
    inv_dt = 1.0 / dt
    for c in range(rows.shape[0]):
        f = facet[c]
        if f < 0:
            continue
        i = rows[c]
        m = mass[i]
        cp = np.zeros(3)
        vw = np.zeros(3)
        gi = np.zeros((3, 3))  # compliance of the surface point (1/kg), world axes
        for k in range(3):
            node = tri[f, k]
            w = weight[c, k]
            for d in range(3):
                cp[d] += w * pts[node, d]
                vw[d] += w * vel[node, d]
                for e in range(3):
                    gi[d, e] += w * share[node] * invm[node, d, e]
        gap = cp - y[i]
        depth = np.sqrt(gap[0] ** 2 + gap[1] ** 2 + gap[2] ** 2)
        if depth == 0.0:
            continue
        nn = gap / depth
        # how far the particle was already behind the surface at the drift's start (the
        # surface moved otherwise than predicted): no impulse for that part, which would
        # push the particle out faster than it came in and create energy
        before = 0.0
        for k in range(3):
            node = tri[f, k]
            for d in range(3):
                before += weight[c, k] * (pts0[node, d] - y_old[i, d]) * nn[d]
        closing = depth - max(before, 0.0)
        if closing <= 0.0:
            continue
        kn = _quadratic(1.0 / m, gi, nn)
        jn = closing * inv_dt / kn        # closes the gap in the step (Eq. 5 when 1/M_s = 0)
        p = jn * nn                       # impulse on the particle, N s
        if friction > 0.0:
            rt = np.empty(3)
            for d in range(3):
                gp = gi[d, d] * p[d]
                for e in range(3):
                    if e != d:
                        gp += gi[d, e] * p[e]
                rt[d] = v[i, d] + p[d] / m - (vw[d] - gp)
            rn = rt[0] * nn[0] + rt[1] * nn[1] + rt[2] * nn[2]
            for d in range(3):
                rt[d] -= rn * nn[d]
            vt = np.sqrt(rt[0] ** 2 + rt[1] ** 2 + rt[2] ** 2)
            if vt > 0.0:
                kt = _quadratic(1.0 / m, gi, rt / vt)
                jt = min(vt / kt, friction * jn)      # Coulomb: stick, or slide at mu jn
                for d in range(3):
                    p[d] -= jt * rt[d] / vt
        for d in range(3):
            dv = p[d] / m
            y[i, d] = y_old[i, d] + dt * (v[i, d] + dv)
            v[i, d] += dv
            particle_impulse[c, d] = p[d]
        for d in range(3):
            totals[d] -= p[d]
        totals[3] += 1.0


def _local(share: np.ndarray) -> np.ndarray:
    """The contact weights per surface node as they are (one process holds every particle)."""
    return share


@dataclass
class ContactStep:
    """What one :meth:`SurfaceContact.resolve` call did (SI)."""

    contacts: int
    impulse: np.ndarray        # (3,) impulse given to the structure, N s
    rows: np.ndarray           # (K,) the particles given an impulse, ascending
    row_impulse: np.ndarray    # (K, 3) their impulses, N s


class SurfaceContact:
    """Contact of one ice body with one structure's contact surface.

    Parameters
    ----------
    surface
        A :class:`pdfem.fem.surface.ContactSurface` (elastic structure or rigid body).
    search_radius
        How far behind the surface (m) a particle is still caught; it must exceed the largest
        penetration in one step (relative speed x step) and stay below half the thinnest wall.
        Half the ice lattice spacing is a good choice.
    friction
        Coulomb friction coefficient between ice and structure (0 = frictionless).
    name
        Name of the contact pair (for messages and results).
    reduce
        ``reduce(share) -> share``: sums the per-node contact weights over the processes that
        hold parts of the ice (an MPI ``allreduce``); default: the weights as they are.

    Notes
    -----
    The contacts' impulses are kept (:class:`pdfem.coupling.nodal_impulse.ContactRecords`) until
    :meth:`take_impulse` hands their nodal sum over, so several ice substeps can be summed into
    one load on the structure; :attr:`node_impulse` shows the sum so far of this process.
    """

    def __init__(self, surface, search_radius: float, friction: float = 0.0,
                 name: str = "contact", reduce=_local) -> None:
        if not search_radius > 0.0:
            raise ValueError(f"search_radius must be > 0, got {search_radius}")
        if friction < 0.0:
            raise ValueError(f"friction must be >= 0, got {friction}")
        self.surface = surface
        self.name = name
        self.search_radius = float(search_radius)
        self.friction = float(friction)
        self.reduce = reduce
        points = np.ascontiguousarray(surface.surface_points(), dtype=np.float64)
        self.topology = FacetTopology.from_triangles(surface.surface_triangles, len(points))
        # the facets near the particles, the grid of those and the particles near the grid,
        # each kept with a skin of the search radius
        self.near = NearFacets(self.topology, len(points), self.search_radius,
                               self.search_radius)
        self.grid = FacetGrid(self.topology.triangles, self.search_radius)
        self.candidates = Candidates(self.search_radius)
        self.records = ContactRecords(len(points), self.topology.triangles)
        self.total_impulse = np.zeros(3)
        self._points = self._velocities = self._start = None
        # the whole surface's normals once (a facet of zero area is refused here); then only
        # the near part's rows are kept current (near_surface)
        self._normals = pseudo_normals(points, self.topology)
        self._normal_points = points       # the positions the normals are taken at
        self._normals_current = False      # whether the near part's rows are of those
        # a surface that moves rigidly: its normals are the reference normals rotated
        self._rotation0 = surface.surface_rotation()
        self._normals_rotation = None
        self._ref_normals = None if self._rotation0 is None else self._normals
        self._facet = self._weight = self._normal = None
        self.set_surface(points, surface.surface_velocities())

    def set_surface(self, points: np.ndarray, velocities: np.ndarray,
                    normals: bool = True, start: np.ndarray | None = None) -> None:
        """Use these node positions (m) and velocities (m/s) for the next contacts (e.g. the
        structure's state interpolated to the ice substep's time). ``normals=False`` keeps the
        pseudo-normals of the last call (they only decide which side a particle is on; within
        a coupling step the surface turns by a negligible angle). ``start``: the node positions
        at the start of the particles' drift (default ``points``: a surface at rest).

        The arrays are kept, not copied: the caller leaves them as they are (the coupler
        passes new ones every substep). The pseudo-normals of a deforming surface are taken at
        these positions by :meth:`near_surface`, for the facets near the particles only; those
        of a surface that moves rigidly are its reference normals turned, here."""
        self._points = np.ascontiguousarray(points, dtype=np.float64)
        self._velocities = np.ascontiguousarray(velocities, dtype=np.float64)
        self._start = (self._points if start is None
                       else np.ascontiguousarray(start, dtype=np.float64))
        self.compliance = self.surface.surface_compliance()
        if not normals:
            return
        if self._rotation0 is None:
            self._normal_points = self._points
            self._normals_current = False
        else:
            self._turn_normals()

    def near_surface(self, y: np.ndarray) -> None:
        """Make the part of the surface near the particles ``y`` ((N, 3), m, float64,
        C-contiguous) ready for their contacts: the facets a particle can reach and their
        grid, chosen again when the surface or the particles have moved more than the skin
        since (:class:`pdfem.coupling.near_facets.NearFacets`), and the pseudo-normals of
        those facets, their edges and vertices at the positions of the last
        :meth:`set_surface` with ``normals`` (the whole surface's numbers, bit for bit)."""
        if not self.near.valid(self._points, y):
            self.near.build(self._points, y)
            self.grid.build(self._points, self.near.facets)
            self._normals_current = False
        if not self._normals_current and self._rotation0 is None:
            pseudo_normals_of(self._normal_points, self.topology, self.near.part,
                              self._normals)
        self._normals_current = True

    def _turn_normals(self) -> None:
        """The pseudo-normals of a surface that moves rigidly: the reference normals turned by
        the rotation since the start (once per change of rotation: a surface that only
        translates keeps them)."""
        rotation = self.surface.surface_rotation()
        if self._normals_rotation is None or not np.array_equal(rotation, self._normals_rotation):
            turn = rotation @ self._rotation0.T
            self._normals = tuple(np.ascontiguousarray(n @ turn.T) for n in self._ref_normals)
            self._normals_rotation = rotation.copy()

    @property
    def pseudo_normals(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The (face, edge, vertex) pseudo-normals in use ((T, 3), (E, 3), (Ns, 3)): current
        in the rows of the near part (:attr:`near`) after :meth:`near_surface`, the rows
        elsewhere left from earlier steps."""
        return self._normals

    def _grid_arrays(self) -> GridArrays:
        g = self.grid
        return GridArrays(g.cell_start, g.cell_facets, g.origin, g.inv_h, g.dims)

    def _surface_arrays(self) -> SurfaceArrays:
        t, nr = self.topology, self._normals
        return SurfaceArrays(self._points, t.triangles, t.tri_edges, nr[0], nr[1], nr[2],
                             t.boundary_edge, t.boundary_node)

    def _buffers(self, n: int) -> None:
        if self._facet is None or len(self._facet) != n:
            self._facet = np.empty(n, dtype=np.int32)
            self._weight = np.empty((n, 3))
            self._normal = np.empty((n, 3))

    def resolve(self, y: np.ndarray, y_old: np.ndarray, v: np.ndarray, mass: np.ndarray,
                dt: float, active: np.ndarray | None = None,
                ids: np.ndarray | None = None) -> ContactStep:
        """Push particles that crossed the surface back and give each contact its impulse (in
        place on ``y`` and ``v``; the structure's share is kept for :meth:`take_impulse`).

        Parameters
        ----------
        y
            (N, 3) particle positions after the position update (m); corrected in place.
        y_old
            (N, 3) positions before the update (m).
        v
            (N, 3) velocities used for the update (m/s); corrected in place.
        mass
            (N,) particle masses rho V (kg).
        dt
            The step (s) from ``y_old`` to ``y``.
        active
            (N,) bool, particles that may touch this surface (default all).
        ids
            (N,) global numbers of the particles (default ``arange(N)``): the structure's
            share is summed in this order, whatever the split over MPI ranks.

        Returns
        -------
        ContactStep
        """
        n = len(y)
        if active is None:
            active = np.ones(n, dtype=np.bool_)
        if ids is None:
            ids = np.arange(n)
        self.near_surface(y)
        g = self.grid
        rows = self.candidates.update(y, g.origin, g.origin + g.dims / g.inv_h, g.builds)
        self._buffers(len(rows))
        t = self.topology
        _detect(len(rows) >= PARALLEL_CANDIDATES, y, rows, active, self._grid_arrays(),
                self._surface_arrays(), self.search_radius, self._facet, self._weight,
                self._normal)
        counts = np.zeros(len(self._points), dtype=np.int64)
        _shares(self._facet, self._weight, t.triangles, counts)
        share = np.asarray(self.reduce(counts), dtype=np.float64) / SHARE_UNIT
        compliance, share = self.compliance.for_contacts(share)
        totals = np.zeros(4)
        per_row = np.zeros((len(rows), 3))
        _respond(rows, self._facet, self._weight, Drift(y, y_old, v, mass), float(dt),
                 SurfaceState(self._points, self._start, self._velocities, compliance,
                              share, t.triangles), self.friction, per_row, totals)
        near = np.flatnonzero(self._facet >= 0)     # only these can have an impulse
        k = near[per_row[near].any(axis=1)]
        hit = rows[k]
        facets = self._facet[k]
        normal = np.einsum("ij,ij->i", per_row[k], self._normals[0][facets])  # pressing
        self.records.add(ids[hit], facets, self._weight[k], per_row[k], normal)
        impulse = totals[:3].copy()
        self.total_impulse += impulse
        return ContactStep(int(totals[3]), impulse, hit, per_row[k])

    @property
    def node_impulse(self) -> np.ndarray:
        """(Ns, 3) nodal impulses (N s) of this process's contacts since :meth:`take_impulse`."""
        return self.records.local()

    def take_impulse(self, allgather: Callable[[list], list] | None = None) -> np.ndarray:
        """The nodal impulses (Ns, 3) (N s) of the contacts since the last call, summed in
        global particle order over the processes (``allgather(x)``: every process's ``x``, in
        rank order; default: this process alone), and forget those contacts."""
        return self.records.take(allgather)

    def take_facet_impulse(self) -> tuple[np.ndarray, np.ndarray]:
        """Per facet, ``(impulse (F, 3), normal (F,))`` (N s) of the contacts handed over by
        :meth:`take_impulse` since the last call (:meth:`ContactRecords.take_facets`)."""
        return self.records.take_facets()

    def inside(self, y: np.ndarray) -> np.ndarray:
        """(N,) bool: particles behind the surface within the search radius (no particle or
        impulse changed; the part of the surface near ``y`` is made ready for them)."""
        n = len(y)
        y = np.ascontiguousarray(y, dtype=np.float64)
        self.near_surface(y)
        self._buffers(n)
        _detect(n >= PARALLEL_CANDIDATES, y,
                np.arange(n), np.ones(n, dtype=np.bool_), self._grid_arrays(),
                self._surface_arrays(), self.search_radius, self._facet, self._weight,
                self._normal)
        return self._facet >= 0


def overlapping(surface, y: np.ndarray, depth: float) -> np.ndarray:
    """(N,) bool: points behind ``surface`` by up to ``depth`` (m), e.g. ice that would start
    inside a structure. A check for set-up, not for every step."""
    return SurfaceContact(surface, depth).inside(y)
