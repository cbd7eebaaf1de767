"""The contact halo of an MPI rank: other ranks' particles near its own, kept with a Verlet skin.

Short-range contact (:mod:`pdfem.forces.short_range`) acts between particles closer than the
cut-off h (the largest critical distance), whatever body or rank they belong to, and fragments
move, so the static bond halo of a split body (:mod:`pdfem.pd.layout.halo`) does not serve.
:class:`ContactHalo` keeps, on each rank, its owned particles (of all bodies) plus *ghosts*:
the particles of other ranks (none on one process) that were within ``h + s`` of the box of the rank's owned
particles at the last *refresh*. ``s`` is the Verlet skin, :data:`SKIN_FRACTION` times h.

Between refreshes the ghost set is fixed and only the ghosts' positions travel, point to point
between the neighbour ranks found at the refresh. A refresh is due when some particle (any
rank) has moved more than s/2 from where it was at the last refresh: until then every pair
closer than h at the current positions was closer than h + s at the refresh (each end moved
less than s/2), so every partner of an owned particle is local. The contact's Verlet pair list
is built at each refresh, for the same reason with the same skin. Each step costs one
collective (an all-gather of each rank's box, its largest squared drift and two flags); a
refresh adds one point-to-point count exchange and one exchange of the ghosts' positions and
constants (global number, reference position, volume, contact constant, radius, body).

The skin: 0.3 h. A thicker skin means fewer refreshes but more ghosts (the shell of ghosts is
``h + s`` thick, so 0.3 h costs 30 % more ghosts than the bare cut-off) and more candidates in
the pair list (an intact cubic lattice has 26 per particle, the sites out to sqrt(3) dx <
1.35 dx + s = 1.755 dx, none of them interacting); a refresh is due when a particle moved
0.15 h ~ 0.2 dx, which ice fragments at 20 m/s with steps of 1e-7-1e-6 s take hundreds of
steps to do, so refreshes are rare and the ghost shell stays thin.

The owned set can change during a run (load balancing moves particles between ranks): a change
of a body's layout (its ``layout``, ``layout.gid`` or ``layout.owned`` objects) is detected at
the next call and forces a refresh on all ranks; :meth:`ContactHalo.invalidate` forces one too.

Local arrays (positions, constants) are in global order (body offset + index in the body), the
serial run's order. Units: m, m^3, N/m^7.
"""

from __future__ import annotations

import numpy as np

from pdfem.forces.short_range_kernels import NOT_FINITE, load_owned
from pdfem.geometry.cell_hash import bounding_box, in_box

#: the Verlet skin s over the cut-off h (see the module text for the choice)
SKIN_FRACTION = 0.3
_COLUMNS = 11  # a ghost's record: gid, y (3), x0 (3), vol, stiffness, radius, body


class ContactHalo:
    """A rank's owned particles and contact ghosts, refreshed with a Verlet skin.

    Parameters
    ----------
    bodies
        The :class:`~pdfem.pd.body.IceBody` bodies (``layout.gid``, ``layout.owned``, ``y``,
        ``x0``, ``vol``).
    offsets
        (n_bodies + 1,) first global number of each body's particles (whole bodies).
    stiffness, radius
        Per body: the short-range constant k (N/m^7) and the particle radius dx / 2 (m).
    cut_off
        The largest critical distance h (m).
    comm
        The communicator.

    Attributes
    ----------
    m
        Local particles (owned and ghosts).
    y, x0, vol, stiffness, radius, body, owned
        Their positions (m, updated every call), reference positions (m), volumes (m^3),
        constants, body numbers and whether this rank owns them, in global order.
    own_pos
        (n_own,) local index of each owned particle (bodies in turn, each in local order).
    n_ghosts, refreshes, neighbours
        Ghosts held, refreshes so far, and the ranks ghosts are exchanged with.
    moved
        Whether the last call found any local position (on any rank) other than the one the
        call before left, or refreshed: False means ``y`` is what it was, bit for bit.
    largest_move
        The largest distance (m) any particle, on any rank, has moved since the last refresh
        (0 right after one).
    """

    def __init__(self, bodies: list, offsets: np.ndarray, stiffness: list, radius: list,
                 cut_off: float, comm) -> None:
        self.bodies = bodies
        self.offsets = np.asarray(offsets, dtype=np.int64)
        self.k_body = [float(k) for k in stiffness]
        self.r_body = [float(r) for r in radius]
        self.comm = comm
        self.skin = SKIN_FRACTION * float(cut_off)
        self.margin = float(cut_off) + self.skin
        self._limit2 = (0.5 * self.skin) ** 2
        self._seen: list | None = None
        self._stale = True
        self.refreshes = 0
        self.n_ghosts = 0
        self.neighbours: list[int] = []
        self.m = 0
        self.moved = True
        self.largest_move = 0.0

    def invalidate(self) -> None:
        """Force a refresh at the next call (e.g. after particles moved between ranks)."""
        self._stale = True

    # -- the owned particles -----------------------------------------------------------------
    def _plans(self) -> list:
        return [(b.layout, b.layout.gid, b.layout.owned) for b in self.bodies]

    def _owned_changed(self) -> bool:
        if self._seen is None:
            return True
        return any(any(a is not b for a, b in zip(now, seen))
                   for now, seen in zip(self._plans(), self._seen))

    def _take_owned(self) -> None:
        """The owned particles' local indices, global numbers and constants."""
        self._seen = self._plans()
        self._stale = True
        self.own = [np.flatnonzero(b.layout.owned) for b in self.bodies]
        rec = []
        for k, (b, o) in enumerate(zip(self.bodies, self.own)):
            r = np.empty((len(o), _COLUMNS))
            r[:, 0] = b.layout.gid[o] + self.offsets[k]
            r[:, 4:7] = b.x0[o]
            r[:, 7] = b.vol[o]
            r[:, 8] = self.k_body[k]
            r[:, 9] = self.r_body[k]
            r[:, 10] = k
            rec.append(r)
        self._own_rec = np.concatenate(rec)

    def positions(self) -> np.ndarray:
        """(n_own, 3) current positions of the owned particles, m."""
        if len(self.bodies) == 1:
            return np.ascontiguousarray(self.bodies[0].y[self.own[0]])
        return np.concatenate([b.y[o] for b, o in zip(self.bodies, self.own)])

    # -- every call ------------------------------------------------------------------------------
    def update(self) -> None:
        """Bring the local positions up to date, refreshing the ghosts when due (then
        ``refreshes`` grows by one). Collective."""
        if self._owned_changed():
            self._take_owned()
        box = np.array([[np.inf] * 3, [-np.inf] * 3])
        due = self._stale
        moved = True
        if due:  # no local arrays for these owned particles yet
            y_own = self.positions()
            finite, drift = True, 0.0
            if len(y_own):
                lo, hi, finite = bounding_box(y_own)
                box = np.array([lo, hi])
        else:  # owned positions straight into the local array
            finite, drift, k, moved = True, 0.0, 0, False
            for b, o in zip(self.bodies, self.own):
                ok, drift, changed = load_owned(b.y, o, self.own_pos[k:k + len(o)], self.y,
                                                self._y_ref, box, drift)
                finite, moved = finite and ok, moved or changed
                k += len(o)
        row = np.concatenate([box[0], box[1], [drift, 0.0 if finite else 1.0, float(due),
                                                float(moved)]])
        table = np.array(self.comm.allgather(row))
        if table[:, 7].any():
            raise FloatingPointError(NOT_FINITE)
        self.moved = bool(table[:, 9].any())
        if table[:, 8].any() or table[:, 6].max() > self._limit2:
            self._refresh(self.positions(), table)
            self.moved, self.largest_move = True, 0.0
        else:
            self.largest_move = float(np.sqrt(table[:, 6].max()))
            if self.moved:  # (unmoved owners: the ghosts are where they were too)
                self._move()

    def _move(self) -> None:
        """Between refreshes: the ghosts' positions from their owners (point to point)."""
        sends = {q: self.y[p] for q, p in self._send.items()}
        recvs = {q: ((n, 3), np.float64) for q, n in self._recv.items()}
        got = self.comm.exchange(sends, recvs) if (sends or recvs) else {}
        if got:
            self.y[self._ghost_pos] = np.concatenate([got[q] for q in sorted(got)])

    def _refresh(self, y_own: np.ndarray, table: np.ndarray) -> None:
        """New ghosts: our particles within h + s of each other rank's box go to that rank."""
        comm, me, g = self.comm, self.comm.rank, self.margin
        # ranks whose boxes come within 2 (h + s) of ours (a symmetric relation, so both sides
        # agree on whom to exchange counts with); none for a rank without particles
        boxes = table[:, :6]
        ok = np.all(np.isfinite(boxes), axis=1)
        partners = [q for q in range(comm.size) if q != me and ok[q] and ok[me]
                    and np.all(boxes[q, :3] - g <= boxes[me, 3:] + g)
                    and np.all(boxes[me, :3] - g <= boxes[q, 3:] + g)]
        self._send = {}
        for q in partners:
            idx = in_box(y_own, boxes[q, :3] - g, boxes[q, 3:] + g)
            if len(idx):
                self._send[q] = idx
        counts = comm.exchange({q: np.array([len(self._send.get(q, ()))], dtype=np.int64)
                                for q in partners},
                               {q: ((1,), np.int64) for q in partners}) if partners else {}
        self._recv = {q: int(v[0]) for q, v in counts.items() if v[0] > 0}
        sends = {}
        for q, idx in self._send.items():
            r = self._own_rec[idx].copy()
            r[:, 1:4] = y_own[idx]
            sends[q] = r
        recvs = {q: ((n, _COLUMNS), np.float64) for q, n in self._recv.items()}
        got = comm.exchange(sends, recvs) if (sends or recvs) else {}
        rec = self._own_rec.copy()
        rec[:, 1:4] = y_own
        rec = np.concatenate([rec] + [got[q] for q in sorted(got)])
        gid = rec[:, 0].astype(np.int64)
        order = np.argsort(gid, kind="stable")
        where = np.empty(len(gid), dtype=np.int64)
        where[order] = np.arange(len(gid))
        n_own = len(y_own)
        self.own_pos, self._ghost_pos = where[:n_own], where[n_own:]
        rec = rec[order]
        self.m = len(rec)
        self.gid = gid[order]
        self.y = np.ascontiguousarray(rec[:, 1:4])
        self.x0 = np.ascontiguousarray(rec[:, 4:7])
        self.vol = np.ascontiguousarray(rec[:, 7])
        self.stiffness = np.ascontiguousarray(rec[:, 8])
        self.radius = np.ascontiguousarray(rec[:, 9])
        self.body = rec[:, 10].astype(np.int32)
        self.owned = np.zeros(self.m, dtype=np.bool_)
        self.owned[self.own_pos] = True
        self.n_ghosts = self.m - n_own
        self.neighbours = sorted(set(self._send) | set(self._recv))
        self._send = {q: self.own_pos[i] for q, i in self._send.items()}  # local positions
        self._y_ref = self.y.copy()
        self._stale = False
        self.refreshes += 1
