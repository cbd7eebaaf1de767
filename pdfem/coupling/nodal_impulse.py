"""The structure's share of the contact impulses, summed in one fixed order on any rank split.

Each contact gives its facet's three nodes the opposite of the particle's impulse, by the
barycentric weights of the contact point (seed paper, Eqs. 7-8). Floating-point sums depend on
their order, and a sum per MPI rank followed by a sum over ranks is not the serial sum: the
difference, 1e-16 relative, is amplified where bonds break, until 1 and N ranks drift apart
by 1e-4. So the contacts are kept (global particle number, facet, weights, impulse) until
they are handed over, gathered from every rank, and summed contact by contact in the order
(resolve call, global particle number): the serial run's order, bit for bit. The same contacts,
in the same order, are also summed per facet (:func:`scatter_facets`): the impulse each facet
took (N s, its share of the facet loads of :mod:`pdfem.coupling.facet_loads`) and its normal
part, for the contact pressure.
Units: N s.
"""

from __future__ import annotations

from collections.abc import Callable

import numba
import numpy as np


@numba.njit(cache=True)
def scatter(facet, weight, impulse, tri, node_impulse):
    """Give contact ``c``'s opposite impulse ``-impulse[c]`` (N s) to the nodes of its facet by
    its barycentric weights (Eqs. 7-8), contact by contact in the order given."""
    for c in range(facet.shape[0]):
        f = facet[c]
        for k in range(3):
            node = tri[f, k]
            w = weight[c, k]
            for d in range(3):
                node_impulse[node, d] -= w * impulse[c, d]


@numba.njit(cache=True)
def scatter_facets(facet, impulse, normal, facet_impulse, facet_normal):
    """Add contact ``c``'s opposite impulse ``-impulse[c]`` (N s) to its facet's row of
    ``facet_impulse`` and its normal impulse ``normal[c]`` (N s, pressing on the facet) to
    ``facet_normal``, contact by contact in the order given."""
    for c in range(facet.shape[0]):
        f = facet[c]
        facet_normal[f] += normal[c]
        for d in range(3):
            facet_impulse[f, d] -= impulse[c, d]


class ContactRecords:
    """The contacts of one contact pair since the last hand-over, one entry per resolve call.

    Parameters
    ----------
    n_nodes
        Number of surface nodes.
    triangles
        (F, 3) node numbers of the surface facets.
    """

    def __init__(self, n_nodes: int, triangles: np.ndarray) -> None:
        self.n_nodes = int(n_nodes)
        self.triangles = triangles
        self.calls: list[tuple[np.ndarray, ...]] = []
        # per facet, since take_facets: impulse on the structure and its normal part, N s
        self.facet_impulse = np.zeros((len(triangles), 3))
        self.facet_normal = np.zeros(len(triangles))

    def add(self, ids: np.ndarray, facet: np.ndarray, weight: np.ndarray,
            impulse: np.ndarray, normal: np.ndarray | None = None) -> None:
        """The contacts of one resolve call: global particle numbers (C,), facets (C,),
        barycentric weights (C, 3), the particles' impulses (C, 3) (N s) and their components
        along the facets' outward normals (C,) (N s, the normal impulse pressing on the facet;
        default 0)."""
        normal = np.zeros(len(facet)) if normal is None else normal
        self.calls.append((np.asarray(ids, dtype=np.int64), np.asarray(facet, dtype=np.int64),
                           np.ascontiguousarray(weight, dtype=np.float64),
                           np.ascontiguousarray(impulse, dtype=np.float64),
                           np.ascontiguousarray(normal, dtype=np.float64)))

    def _sum(self, calls: list, facets: bool = False) -> np.ndarray:
        out = np.zeros((self.n_nodes, 3))
        for ids, facet, weight, impulse, normal in calls:
            order = np.argsort(ids, kind="stable")
            scatter(facet[order], weight[order], impulse[order], self.triangles, out)
            if facets:
                scatter_facets(facet[order], impulse[order], normal[order], self.facet_impulse,
                               self.facet_normal)
        return out

    def local(self) -> np.ndarray:
        """(Ns, 3) nodal impulses (N s) of this process's contacts so far (kept)."""
        return self._sum(self.calls)

    def take(self, allgather: Callable[[list], list] | None = None) -> np.ndarray:
        """(Ns, 3) nodal impulses (N s) of the contacts of every process (``allgather(x)``: the
        list of every process's ``x`` in rank order; default this process alone), summed in
        the order (call, global particle number); the contacts are then forgotten."""
        calls, self.calls = self.calls, []
        if allgather is None:
            return self._sum(calls, facets=True)
        parts = allgather(calls)
        merged = [tuple(np.concatenate([rank[k][j] for rank in parts]) for j in range(5))
                  for k in range(len(calls))]
        return self._sum(merged, facets=True)

    def take_facets(self) -> tuple[np.ndarray, np.ndarray]:
        """``(impulse (F, 3), normal (F,))``: per facet, the impulse (N s) the structure took
        and its normal part pressing on the facet (N s), from the contacts handed over by
        :meth:`take` since the last call (the same on every process); then zero."""
        out = self.facet_impulse, self.facet_normal
        self.facet_impulse = np.zeros_like(out[0])
        self.facet_normal = np.zeros_like(out[1])
        return out
