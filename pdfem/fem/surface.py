"""The contact surface of a structure: the interface that the contact code sees.

Elastic structures (:class:`pdfem.fem.structure.ElasticStructure`) and rigid bodies
(:class:`pdfem.motion.rigid.RigidBody`) expose the same surface interface, :class:`ContactSurface`:
current positions and velocities of the surface nodes, triangles over them with outward unit
normals, and an accumulator for the nodal contact forces (N) they receive, with its total force
and moment. :class:`SurfaceBody` implements the force bookkeeping and the normals once for both.

This module also holds the triangle helpers both need: splitting quadrilateral faces, unit
normals, and orienting a triangulated surface consistently and outward.
"""

from __future__ import annotations

from collections import deque
from typing import Protocol, runtime_checkable

import numpy as np
import scipy.sparse as sp

from pdfem.geometry.vectors import cross


@runtime_checkable
class ContactSurface(Protocol):
    """What a body offers to the contact code (SI: m, m/s, N, N m)."""

    surface_triangles: np.ndarray  # (T, 3) int32 indices into the surface nodes

    def surface_points(self) -> np.ndarray:
        """(Ns, 3) current positions of the surface nodes (m)."""
        ...

    def surface_velocities(self) -> np.ndarray:
        """(Ns, 3) current velocities of the surface nodes (m/s)."""
        ...

    def facet_normals(self) -> np.ndarray:
        """(T, 3) unit normals pointing out of the body, current configuration."""
        ...

    def surface_compliance(self):
        """How far the surface gives way per unit impulse over a contact (1/kg): a
        :mod:`pdfem.fem.step_compliance` object with ``for_contacts(share)``."""
        ...

    def surface_rotation(self) -> np.ndarray | None:
        """(3, 3) rotation from the reference configuration if the surface moves rigidly, else
        ``None``."""
        ...

    def add_surface_forces(self, forces: np.ndarray) -> None:
        """Accumulate (Ns, 3) nodal forces (N) for the next step."""
        ...

    def clear_surface_forces(self) -> None:
        """Reset the accumulated surface forces to zero."""
        ...

    def total_surface_force(self) -> np.ndarray:
        """(3,) sum of the accumulated surface forces (N)."""
        ...

    def total_surface_moment(self, about) -> np.ndarray:
        """(3,) moment (N m) of the accumulated surface forces about a point (current positions)."""
        ...

    def step(self, dt: float) -> None:
        """Advance the body by ``dt`` (s)."""
        ...

    def stable_time_step(self) -> float:
        """Largest stable step (s); ``inf`` if unlimited."""
        ...


def split_quads(faces: np.ndarray) -> np.ndarray:
    """(F, 3) triangles as they are, (F, 4) quadrilaterals split along 0-2 into (2F, 3) triangles.

    The split keeps each face's orientation: quad (a, b, c, d) -> (a, b, c), (a, c, d), in place
    (triangles 2i and 2i+1 come from quad i).
    """
    faces = np.asarray(faces)
    if faces.ndim != 2 or faces.shape[1] not in (3, 4):
        raise ValueError(f"faces must be (F, 3) or (F, 4), got {faces.shape}")
    if faces.shape[1] == 3:
        return faces.astype(np.int32)
    out = np.empty((2 * len(faces), 3), dtype=np.int32)
    out[0::2] = faces[:, [0, 1, 2]]
    out[1::2] = faces[:, [0, 2, 3]]
    return out


def triangle_normals(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(T, 3) unit normals by the right-hand rule of each triangle's node order."""
    x = points[triangles]
    n = cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    return n / np.linalg.norm(n, axis=1)[:, None]


def orient_outward(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Orient a triangulated surface consistently and, where it is closed, outward.

    Within each edge-connected patch, neighbouring triangles are made to traverse their shared
    edge in opposite directions (orientation of the patch's first triangle kept). A patch whose
    every edge has exactly two triangles is closed; it is flipped if its enclosed volume
    (divergence theorem) comes out negative, so its normals point outward. Open patches keep the
    orientation of their first triangle.

    Parameters
    ----------
    points
        (N, 3) node coordinates (m).
    triangles
        (T, 3) node indices.

    Returns
    -------
    numpy.ndarray
        (T, 3) int32 triangles, re-ordered where needed.

    Raises
    ------
    ValueError
        If an edge is shared by more than two triangles or the surface is not orientable.
    """
    tri = np.asarray(triangles, dtype=np.int64).copy()
    nt = len(tri)
    if nt == 0:
        return tri.astype(np.int32)
    e = np.stack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]], axis=1).reshape(-1, 2)
    key = np.sort(e, axis=1)
    uniq, inv, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    if count.max() > 2:
        raise ValueError(f"the surface has {int((count > 2).sum())} edges shared by more than two "
                         "triangles; it is not a manifold surface")
    owner = np.repeat(np.arange(nt), 3)
    forward = e[:, 0] < e[:, 1]                 # direction of each directed edge vs its key
    order = np.argsort(inv, kind="stable")
    shared = count[inv[order]] == 2
    pairs = order[shared].reshape(-1, 2)        # the two directed edges of each interior edge
    ta, tb = owner[pairs[:, 0]], owner[pairs[:, 1]]
    # same traversal direction on a shared edge -> the two triangles disagree in orientation
    disagree = forward[pairs[:, 0]] == forward[pairs[:, 1]]
    rel = sp.coo_matrix((disagree.astype(np.int8) + 1, (ta, tb)), shape=(nt, nt)).tocsr()
    rel = (rel + rel.T).tocsr()                 # 1 = agree, 2 = disagree (per neighbour pair)
    if rel.nnz and rel.data.max() > 2:
        raise ValueError("two surface triangles share more than one edge (duplicate triangles)")
    indptr, indices, data = rel.indptr, rel.indices, rel.data
    flip = np.full(nt, -1, dtype=np.int8)
    comp = np.full(nt, -1, dtype=np.int64)
    ncomp = 0
    for start in range(nt):                     # setup-time traversal, once per surface
        if flip[start] >= 0:
            continue
        flip[start] = 0
        comp[start] = ncomp
        queue = deque([start])
        while queue:
            t = queue.popleft()
            for k in range(indptr[t], indptr[t + 1]):
                nb = indices[k]
                want = flip[t] ^ (1 if data[k] == 2 else 0)
                if flip[nb] < 0:
                    flip[nb] = want
                    comp[nb] = ncomp
                    queue.append(nb)
                elif flip[nb] != want:
                    raise ValueError("the surface is not orientable (e.g. a Moebius strip)")
        ncomp += 1
    tri[flip == 1] = tri[flip == 1][:, ::-1]
    # closed patches: every edge of the patch shared by two triangles -> outward by volume sign
    edge_comp = comp[owner]
    open_edge = count[inv] == 1
    closed = np.ones(ncomp, dtype=bool)
    closed[np.unique(edge_comp[open_edge])] = False
    x = points[tri]
    vol6 = np.einsum("ij,ij->i", x[:, 0], cross(x[:, 1], x[:, 2]))
    vol = np.bincount(comp, weights=vol6, minlength=ncomp)
    inward = closed & (vol < 0.0)
    sel = inward[comp]
    tri[sel] = tri[sel][:, ::-1]
    return tri.astype(np.int32)


class SurfaceBody:
    """Shared bookkeeping of the contact surface: forces, totals, normals.

    Subclasses set ``surface_triangles`` and ``_surface_forces`` ((Ns, 3) zeros) and implement
    :meth:`surface_points` and :meth:`surface_velocities`.
    """

    surface_triangles: np.ndarray
    _surface_forces: np.ndarray

    def surface_points(self) -> np.ndarray:  # pragma: no cover - implemented by subclasses
        raise TypeError(f"{type(self).__name__} must implement surface_points()")

    def surface_velocities(self) -> np.ndarray:  # pragma: no cover - implemented by subclasses
        raise TypeError(f"{type(self).__name__} must implement surface_velocities()")

    def surface_state(self) -> tuple[np.ndarray, np.ndarray]:
        """New (Ns, 3) arrays of the surface's positions (m) and velocities (m/s) now (a
        subclass that finds both in one pass gives them together)."""
        return self.surface_points().copy(), self.surface_velocities().copy()

    @property
    def n_surface_nodes(self) -> int:
        """Number of contact-surface nodes Ns."""
        return len(self._surface_forces)

    def facet_normals(self) -> np.ndarray:
        """(T, 3) outward unit normals of the surface triangles in the current configuration."""
        return triangle_normals(self.surface_points(), self.surface_triangles)

    def add_surface_forces(self, forces: np.ndarray) -> None:
        """Accumulate nodal forces (N) on the surface nodes, (Ns, 3); kept until cleared."""
        forces = np.asarray(forces, dtype=np.float64)
        if forces.shape != self._surface_forces.shape:
            raise ValueError(f"surface forces must have shape {self._surface_forces.shape}, "
                             f"got {forces.shape}")
        self._surface_forces += forces

    def clear_surface_forces(self) -> None:
        """Reset the accumulated surface forces to zero."""
        self._surface_forces[:] = 0.0

    def set_surface_forces(self, forces: np.ndarray) -> None:
        """Replace the surface forces (N), (Ns, 3), effective from the current time on: a
        piecewise-constant load, so that a load held over a time T gives the impulse T x load."""
        forces = np.asarray(forces, dtype=np.float64)
        if forces.shape != self._surface_forces.shape:
            raise ValueError(f"surface forces must have shape {self._surface_forces.shape}, "
                             f"got {forces.shape}")
        self._surface_forces[:] = forces

    @property
    def surface_forces(self) -> np.ndarray:
        """(Ns, 3) accumulated surface forces (N), read-only view."""
        view = self._surface_forces.view()
        view.flags.writeable = False
        return view

    def total_surface_force(self) -> np.ndarray:
        """(3,) sum of the accumulated surface forces (N)."""
        return self._surface_forces.sum(axis=0)

    def total_surface_moment(self, about=(0.0, 0.0, 0.0)) -> np.ndarray:
        """(3,) moment (N m) of the accumulated surface forces about ``about`` (m), taken at the
        current node positions."""
        r = self.surface_points() - np.asarray(about, dtype=np.float64).reshape(1, 3)
        return cross(r, self._surface_forces).sum(axis=0)
