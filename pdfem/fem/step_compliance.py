"""The contact compliance of a structure: how far its contact surface gives way per unit impulse
over a contact (1/kg). :class:`LumpedCompliance` is an explicit substep's, the lumped inverse
masses of the nodes; :class:`StepCompliance` an implicit structure's, the 3 x 3 blocks of
``A^-1`` between nearby nodes of its contact surface, by probing, and the response they give to
a step's contacts. Both give the contact (:mod:`pdfem.coupling.contact`) the blocks it resolves
a step's contacts with, :meth:`~StepCompliance.for_contacts`.

Over one average-acceleration Newmark step of ``dt`` (:mod:`pdfem.fem.implicit`) a force ``f``
at the step's end changes the end acceleration by ``A^-1 f``, ``A = M + dt/2 C + dt^2/4 K`` on
the free DOFs, and the mean displacement over the step per unit of impulse by ``A^-1 / 2``
(:meth:`pdfem.fem.implicit.Newmark.end_impulse`). Unlike an explicit substep's lumped mass,
this response couples neighbouring nodes: measured on the milling blades at their coupling
step, a node's block of ``A^-1`` is 0.2-0.8 of the diagonal block of a neighbour 1-5 cm away,
and a uniform load on the whole surface moves a node 3.5 times as far as a load on that node
alone (1.5-1.9 times on the demo panel). So the contact (:mod:`pdfem.coupling.contact`) needs
more than the diagonal: a step's contacts are resolved together with the response of each
surface node ``i`` to the step's pattern of contacts, ``S_i = sum_k C_ik s_k``
(:meth:`StepCompliance.response`), ``s_k`` the contacts' summed barycentric weights at node
``k`` (the nodal *share* of the explicit contact, there with ``C_ik = 0`` for ``i != k``).
A single contact then sees the exact compliance of the point it hits (within its facet's
nodes), and contacts pressing together see their collective response (the row sum of the
compliance between contacts, which bounds its quadratic form when the couplings are
positive: the step's contacts then only dissipate energy).

``A^-1`` is local: a unit force spreads over the step about as far as a pressure wave runs in
half of it, its response decaying with distance ``r`` roughly as ``exp(-r / l)``,
``l = c dt / 2`` (``c`` the pressure-wave speed; ``A = M + dt^2/4 K`` is a discrete modified
Helmholtz operator with decay length ``sqrt(dt^2/4 c^2)``). Blocks are kept between nodes
``REACH`` decay lengths apart: the row sums of a uniform load are then within 1-4 % of their
full value (measured on the milling blades and the demo panel, 30 nodes each; 1-7 % at 4 l).
They are found by *probing* (Curtis, Powell & Reid, *IMA J. Appl. Math.* 13, 1974; Tang &
Saad, *Numer. Linear Algebra Appl.* 19, 2012): the surface nodes are coloured so that nodes of
one colour lie ``radius`` apart, and one solve per colour and component, the unit load on that
component of every node of the colour, gives each of them its column of blocks on the nodes
near it, up to the responses to the colour's other nodes, ``radius - reach`` or more away.
``radius`` = ``REACH`` + 8 decay lengths: the diagonal blocks are within 1e-3 of the exact
ones at 8 l (largest relative Frobenius error of 60 sampled blocks: 6e-5 on the milling
blades, 1e-3 on the demo panel). The blocks are symmetrised, ``C_ik = C_ki^T``. A solve
shared over ranks (blocks of ``A`` dealt out, :mod:`pdfem.fem.block_factor`) gives each rank the
rows of its own blocks; the rows read there go to every rank before the symmetrising, so that
every rank has the blocks of one rank's probing, bit for bit.

Units: kg (``A``), 1/kg (its inverse), m, s.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numba
import numpy as np
from scipy.spatial import cKDTree
from threadpoolctl import threadpool_limits

from pdfem.geometry.cell_hash import members

REACH = 5.0
"""Range of the kept couplings, in decay lengths ``c dt / 2`` (module docstring)."""

CLEAR = 8.0
"""Least distance, in decay lengths, from a node to the other nodes of the colour of a node
whose coupling with it is read (module docstring)."""

BATCH = 96
"""Right-hand sides per call of the solves (the columns of one call share one pass of the kernel
over the blocks)."""


def wave_speed(density: float, youngs_modulus: float, poisson_ratio: float) -> float:
    """Pressure-wave speed (m/s) ``sqrt((lambda + 2 mu) / rho)`` of an isotropic solid."""
    nu = poisson_ratio
    return math.sqrt(youngs_modulus * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu) * density))


def decay_length(speed: float, dt: float, spacing: float) -> float:
    """The decay length (m) of the step's response, ``speed dt / 2``, and at least half the
    largest distance ``spacing`` (m) between neighbouring surface nodes (so that the blocks of
    neighbours are kept and read apart)."""
    return max(0.5 * speed * dt, 0.5 * spacing)


class Coupling(NamedTuple):
    """Blocks ``C_ik`` (1/kg, (nnz, 3, 3)) of node ``i`` with the nodes
    ``index[start[i]:start[i + 1]]`` (ascending, ``i`` among them), row ``i``."""

    start: np.ndarray
    index: np.ndarray
    blocks: np.ndarray


def colours(points: np.ndarray, radius: float) -> np.ndarray:
    """(N,) colour of each point: greedy in point order, the smallest colour that no earlier
    point within ``radius`` (m) has (deterministic)."""
    if len(points) == 0:
        return np.zeros(0, dtype=np.int64)
    pairs = cKDTree(points).query_pairs(radius, output_type="ndarray")   # (m, 2), i < j
    later = pairs[np.lexsort((pairs[:, 0], pairs[:, 1]))]                # by the later point
    start = np.searchsorted(later[:, 1], np.arange(len(points) + 1))
    return _greedy_colours(start, later[:, 0].astype(np.int64))


@numba.njit(cache=True)
def _greedy_colours(start, earlier):
    """Point ``i`` takes the smallest colour that none of ``earlier[start[i]:start[i + 1]]``
    (its neighbours before it) has."""
    n = start.shape[0] - 1
    out = np.full(n, -1, dtype=np.int64)
    seen = np.full(n + 1, -1, dtype=np.int64)     # seen[c] == i: colour c is taken near i
    for i in range(n):
        for p in range(start[i], start[i + 1]):
            seen[out[earlier[p]]] = i
        c = 0
        while seen[c] == i:
            c += 1
        out[i] = c
    return out


def _pairs(points: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """CSR ``(start, index)`` of the node pairs within ``reach`` (m), rows ascending."""
    near = cKDTree(points).query_ball_point(points, reach, return_sorted=True)
    start = np.zeros(len(points) + 1, dtype=np.int64)
    start[1:] = np.cumsum([len(g) for g in near])
    index = np.concatenate([np.asarray(g, dtype=np.int64) for g in near]) if len(near) \
        else np.zeros(0, dtype=np.int64)
    return start, index


def probe(solve: Callable[[np.ndarray], np.ndarray], free_index: np.ndarray,
          node_dofs: np.ndarray, points: np.ndarray, length: float,
          complete: Callable[[np.ndarray, np.ndarray], None] | None = None) -> Coupling:
    """The blocks of ``A^-1`` (1/kg) between the nodes ``node_dofs`` within ``REACH`` decay
    lengths, by probing with colours ``REACH + CLEAR`` decay lengths apart.

    Parameters
    ----------
    solve
        ``X = solve(B)``: ``A X = B`` on the free DOFs, ``B`` of shape (free DOFs, k) (on
        some of the free DOFs only, with ``complete``).
    free_index
        (n,) index of each DOF among the free DOFs, -1 for a held DOF (its rows and columns
        of the blocks are 0).
    node_dofs
        (Ns, 3) the DOF of each node's x, y, z.
    points
        (Ns, 3) node positions (m).
    length
        The decay length (m), :func:`decay_length`.
    complete
        ``complete(blocks, rows)``: fill in the rows of ``blocks`` (P, 3, 3) that ``solve``
        does not give: ``blocks[p, a, :]`` read at the free DOF ``rows[p, a]`` (-1: held) of
        pair ``p``'s node ``i`` (a solve shared over ranks, each solving part of ``A``).
    """
    ns = len(node_dofs)
    start, index = _pairs(points, REACH * length)
    row = np.repeat(np.arange(ns), np.diff(start))
    colour = colours(points, (REACH + CLEAR) * length)
    free = free_index[node_dofs]                            # (Ns, 3)
    n_free = int(free_index.max()) + 1 if free_index.size else 0
    blocks = np.zeros((len(index), 3, 3))
    n_colours = int(colour.max()) + 1 if ns else 0
    nodes_of = members(colour, n_colours)
    free_k, free_i = free[index], free[row]                  # (P, 3): k's and i's free DOFs
    columns = [(c, d) for c in range(n_colours) for d in range(3)]
    for first in range(0, len(columns), BATCH):
        batch = columns[first:first + BATCH]
        rhs = np.zeros((n_free, len(batch)))
        column_of = np.full((n_colours, 3), -1, dtype=np.int64)
        for j, (c, d) in enumerate(batch):
            nodes = nodes_of[c][free[nodes_of[c], d] >= 0]
            rhs[free[nodes, d], j] = 1.0
            column_of[c, d] = j
        with threadpool_limits(limits=1, user_api="blas"):   # (a solve that calls BLAS, e.g.
            x = solve(rhs)                                    # SuperLU's, thrashes threaded: 14x)
        _read_columns(np.ascontiguousarray(x), column_of, colour[index], free_k, free_i,
                      blocks)
    if complete is not None:
        complete(blocks, free_i)
    # C_ik = C_ki^T: the mean of the two probes
    twin = np.lexsort((row, index))                          # pair (k, i) of each (i, k)
    return Coupling(start, index, 0.5 * (blocks + blocks[twin].transpose(0, 2, 1)))


@numba.njit(cache=True)
def _read_columns(x, column_of, colour_k, free_k, free_i, blocks):
    """For each pair ``p`` = (i, k) and direction ``d`` whose column (k's colour, d) is
    ``column_of[colour, d]`` of ``x`` (-1: not in it), k's DOF d free: column d of ``C_ik``,
    ``blocks[p, a, d]`` = the response ``x`` at i's free DOF a (0 where it is held)."""
    for p in range(blocks.shape[0]):
        for d in range(3):
            j = column_of[colour_k[p], d]
            if j < 0 or free_k[p, d] < 0:
                continue
            for a in range(3):
                r = free_i[p, a]
                blocks[p, a, d] = x[r, j] if r >= 0 else 0.0


@numba.njit(cache=True)
def _response(start, index, blocks, share, rotation, out):
    """``out[i] = R (sum_k C_ik share[k]) R^T`` over the rows of the nodes with a share
    (``C_ik = C_ki^T``, read from row k), zero elsewhere; no turn when ``rotation`` is empty."""
    out[:] = 0.0
    hit = np.zeros(out.shape[0], dtype=np.bool_)
    for k in range(share.shape[0]):
        s = share[k]
        if s == 0.0:
            continue
        for p in range(start[k], start[k + 1]):
            i = index[p]
            hit[i] = True
            for a in range(3):
                for b in range(3):
                    out[i, a, b] += s * blocks[p, b, a]
    if rotation.shape[0] == 0:
        return
    tmp = np.empty((3, 3))
    for i in range(out.shape[0]):
        if not hit[i]:
            continue
        for a in range(3):
            for b in range(3):
                tmp[a, b] = (rotation[a, 0] * out[i, 0, b] + rotation[a, 1] * out[i, 1, b]
                             + rotation[a, 2] * out[i, 2, b])
        for a in range(3):
            for b in range(3):
                out[i, a, b] = (tmp[a, 0] * rotation[b, 0] + tmp[a, 1] * rotation[b, 1]
                                + tmp[a, 2] * rotation[b, 2])


class LumpedCompliance:
    """An explicit substep's compliance: each node's lumped inverse mass per component (1/kg,
    zero on held components) as a diagonal block; a node's mass is split among the contacts
    on it by their weights (the contact's share), and no node's response reaches another.

    Parameters
    ----------
    inverse_mass
        (Ns, 3) inverse lumped mass per node and component (1/kg).
    """

    def __init__(self, inverse_mass: np.ndarray) -> None:
        g = np.asarray(inverse_mass, dtype=np.float64)
        self.blocks = np.zeros((len(g), 3, 3))
        for d in range(3):
            self.blocks[:, d, d] = g[:, d]

    def turned(self, rotation: np.ndarray | None) -> "LumpedCompliance":
        """Itself: a lumped mass is the same in every direction (a held component stays held
        in the structure's own axes, as the explicit contact has always taken it)."""
        return self

    def for_contacts(self, share: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(blocks, share)`` for the contact kernel: the diagonal blocks, each scaled there by
        the contacts' summed weights ``share`` at its node."""
        return self.blocks, share


class StepCompliance:
    """The contact compliance of an implicit step (module docstring): coupling blocks of the
    mean displacement over the step per unit impulse (1/kg, the structure's axes) and the
    rotation that turns them into world axes (``None``: the axes are the world's).

    Parameters
    ----------
    coupling
        The blocks, :class:`Coupling`.
    rotation
        (3, 3) rotation from the structure's axes to the world's, or ``None``.
    """

    def __init__(self, coupling: Coupling, rotation: np.ndarray | None = None) -> None:
        self.coupling = coupling
        self.rotation = rotation
        self._out = np.zeros((len(coupling.start) - 1, 3, 3))
        self._ones = np.ones(len(coupling.start) - 1)

    def turned(self, rotation: np.ndarray | None) -> "StepCompliance":
        """The same blocks turned by ``rotation`` (shared, not copied)."""
        return StepCompliance(self.coupling, rotation)

    def diagonal(self) -> np.ndarray:
        """(Ns, 3, 3) the diagonal blocks ``C_ii`` (1/kg), the structure's axes."""
        c = self.coupling
        rows = np.repeat(np.arange(len(c.start) - 1), np.diff(c.start))
        return c.blocks[rows == c.index]

    def response(self, share: np.ndarray) -> np.ndarray:
        """(Ns, 3, 3) ``S_i = R (sum_k C_ik s_k) R^T`` (1/kg, world axes) for the contacts'
        summed weights ``share`` (Ns,) at the nodes (a buffer, overwritten by the next call)."""
        c = self.coupling
        rot = np.zeros((0, 3)) if self.rotation is None else np.ascontiguousarray(self.rotation)
        _response(c.start, c.index, c.blocks, np.ascontiguousarray(share, dtype=np.float64),
                  rot, self._out)
        return self._out

    def for_contacts(self, share: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(blocks, ones)`` for the contact kernel: each node's response to the step's
        contacts, :meth:`response`, which holds the shares already."""
        return self.response(share), self._ones
