"""An ice body split over MPI ranks: owned particles, a halo of ghosts, two exchanges per step.

A rank's part comes either from the global set-up (every rank builds the same global body:
lattice, bonds, weights, deterministic; :class:`DistributedIce` keeps its part) or from the
distributed set-up (:mod:`pdfem.pd.layout.setup`, :meth:`DistributedIce.from_local`: each
rank builds only its part; the same arrays). Either way a rank holds only its *local* part:
the particles it owns (:mod:`pdfem.parallel.partition`) and their bond partners owned
elsewhere (the halo), in global order, and every bond with at least one owned end, in the
global bond order. Bonds only break, so this pattern is fixed until the body is re-partitioned
(:mod:`pdfem.pd.layout.rebalance`: particles and bonds move to new owners, ``layout_version``
increments). One velocity-Verlet step on a rank:

1. half kick and position update of its particles (halo values are overwritten next);
2. exchange: every rank sends the positions of the particles its neighbours hold as halo;
3. dilatation of the local particles (right for owned ones, whose bonds are all local);
4. exchange of the dilatations, so the halo's are right too;
5. forces and bond breaking over the local bonds: a bond between an owned particle and a halo
   particle is evaluated on both ranks from the same positions, so both decide alike;
6. half kick.

Steps 3-5 are the serial body's fused kernel (:func:`pdfem.pd.bonds.kernels.dilatation_and_forces`,
which keeps each bond's length from the dilatation pass for the force pass) with the exchange of
step 4 between its two passes; broken bonds are stored as negative weights, as in the serial body.

The arithmetic per owned particle is the serial code's, on the same values; only the order of
some sums can differ, so 1 and N ranks agree to round-off. Units: SI.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from pdfem.pd.bonds import kernels
from pdfem.pd.body import IceBody
from pdfem.pd.constraints import reaction_forces
from pdfem.pd.failure.crushed_shear import shear_energy_args
from pdfem.pd.checkpoint.split_state import DistributedCheckpoint
from pdfem.pd.layout.surface import halo_exchange
from pdfem.pd.layout.timestep import split_stable_time_step
from pdfem.pd.layout.rebalance import Rebalancing


@dataclasses.dataclass
class HaloPlan:
    """Which particles a rank holds and what it exchanges.

    Attributes
    ----------
    local
        (n_local,) global indices of the local particles, ascending.
    owned
        (n_local,) bool, owned by this rank.
    pairs
        (P_local,) global indices of the local bonds, ascending.
    send, recv
        neighbour rank -> local indices whose values are sent / received, in global order.
    """

    local: np.ndarray
    owned: np.ndarray
    pairs: np.ndarray
    send: dict
    recv: dict


def halo_plan(owner: np.ndarray, row_ptr: np.ndarray, nbr: np.ndarray, rank: int) -> HaloPlan:
    """The :class:`HaloPlan` of ``rank`` for the partition ``owner`` of a pair list."""
    n = len(owner)
    i_of = np.repeat(np.arange(n, dtype=np.int64), np.diff(row_ptr))
    oi, oj = owner[i_of], owner[nbr]
    keep = (oi == rank) | (oj == rank)
    pairs = np.flatnonzero(keep)
    mine = owner == rank
    halo_from_j = nbr[keep & (oi == rank) & (oj != rank)]
    halo_from_i = i_of[keep & (oj == rank) & (oi != rank)]
    halo = np.unique(np.concatenate([halo_from_j, halo_from_i]))
    local = np.union1d(np.flatnonzero(mine), halo)
    g2l = np.full(n, -1, dtype=np.int64)
    g2l[local] = np.arange(len(local))
    owned = mine[local]
    recv = {int(q): g2l[halo[owner[halo] == q]] for q in np.unique(owner[halo])}
    # what q needs from us: our particles bonded to q's particles
    send = {}
    cross = keep & (oi != oj)
    for q in recv:  # halo relations are symmetric: we send to exactly the ranks we receive from
        a = i_of[cross & (oi == rank) & (oj == q)]
        b = nbr[cross & (oj == rank) & (oi == q)]
        send[q] = g2l[np.unique(np.concatenate([a, b]))]
    return HaloPlan(local, owned, pairs, send, recv)


class DistributedIce(DistributedCheckpoint, Rebalancing):
    """This rank's part of an ice body, advanced in step with the other ranks.

    It implements the ice-body interface of :class:`pdfem.pd.ice_interface.IceParticles`, as
    the whole :class:`~pdfem.pd.body.IceBody` does, so the coupler, the particle forces and the
    output treat both alike.

    Parameters
    ----------
    body
        The whole body, built identically on every rank (with its constraints and fixed set).
    owner
        (N,) owner rank of each particle.
    comm
        The communicator (:func:`pdfem.parallel.comm.world`).
    """

    def __init__(self, body: IceBody, owner: np.ndarray, comm) -> None:
        self.comm = comm
        self.global_n = body.n
        self.global_body = body
        plan = halo_plan(np.asarray(owner), body.row_ptr, body.nbr, comm.rank)
        self.plan = plan
        loc, pairs = plan.local, plan.pairs
        g2l = np.full(body.n, -1, dtype=np.int64)
        g2l[loc] = np.arange(len(loc))
        i_of = np.repeat(np.arange(body.n, dtype=np.int64), np.diff(body.row_ptr))[pairs]
        row_ptr = np.zeros(len(loc) + 1, dtype=np.int64)
        np.add.at(row_ptr, g2l[i_of] + 1, 1)
        row_ptr = np.cumsum(row_ptr)
        nbr = g2l[body.nbr[pairs]].astype(np.int32)
        local = dataclasses.replace(
            body, x0=body.x0[loc].copy(), vol=body.vol[loc].copy(), row_ptr=row_ptr, nbr=nbr,
            xi_len=body.xi_len[pairs].copy(),
            nofail=body.nofail[loc].copy(), y=body.y[loc].copy(), v=body.v[loc].copy(),
            f=np.zeros((len(loc), 3)), m=body.m[loc].copy(), theta=np.zeros(len(loc)),
            weight=kernels.signed_weights(body.weight[pairs], body.broken[pairs]),
            flags=None,  # broken bonds are negative weights (replace would copy the flags)
            fixed=body.fixed[loc].copy(), constraints=[],
            loop="pairs", external_work=0.0, fracture_dissipated=0.0,
            rest=None if body.rest is None else body.rest[pairs].copy(), rates=None, gid=loc,
            shear=None if body.shear is None else body.shear.subset(pairs))
        local._ws = kernels.PairWorkspace(row_ptr, nbr)
        for c in body.constraints:
            mine = c.index[np.asarray(owner)[c.index] == comm.rank]
            local.constraints.append(dataclasses.replace(c, index=g2l[mine]))
        self.global_bonds = len(body.nbr)
        self._attach(local)

    @classmethod
    def from_local(cls, local: IceBody, plan: HaloPlan, comm, n_global: int) -> "DistributedIce":
        """A rank's part built without the global body (:mod:`pdfem.pd.layout.setup`):
        ``local`` holds the owned and halo particles in global order (``local.gid`` their
        global numbers, constraints over owned particles only), ``plan`` its halo plan
        (``pairs`` None), ``n_global`` the body's particle count. Collective."""
        self = cls.__new__(cls)
        self.comm = comm
        self.global_n = int(n_global)
        self.global_body = None  # never built: short-range contact needs the global set-up
        self.plan = plan
        counted = np.repeat(plan.owned, np.diff(local.row_ptr))  # 1 B per bond
        self.global_bonds = int(comm.allreduce_sum(np.int64(counted.sum())))
        del counted
        self._attach(local)
        return self

    def _attach(self, local: IceBody) -> None:
        """Take ``local`` as this rank's body and set up the counters (collective)."""
        plan = self.plan
        self.body = local
        self.exchange_seconds = 0.0  # wall time spent in halo exchanges, s
        # bonds whose lower end is owned here: counted once over all ranks
        self._counted = np.repeat(plan.owned, np.diff(local.row_ptr))
        self._counted_broken = self._broken_count()
        self._owned_rows = plan.owned.astype(np.uint8)  # whose crushing energy this rank counts
        self.update_intact_volume()  # pre-cracks: the halo's from their owners

    # -- exchanges ---------------------------------------------------------------------------
    def _exchange(self, values: np.ndarray) -> None:
        """Overwrite the halo entries of ``values`` with their owners' values."""
        self.exchange_seconds += halo_exchange(self.comm, self.plan, values)

    def _broken_count(self) -> int:
        """Broken bonds whose lower end this rank owns (each bond counted on one rank)."""
        return int(self.body.broken[self._counted].sum(dtype=np.int64))

    def _compute_forces(self) -> int:
        """Positions exchanged, then the fused dilatation and force passes with the exchange of
        the dilatations between them; returns the bonds this rank counts as newly broken. The
        energy the broken bonds held at the owned particles goes to the rank's part of
        :attr:`fracture_dissipated` (:mod:`pdfem.pd.failure.fracture`)."""
        b, mat = self.body, self.body.material
        b._ledger.prepare(b)
        self._exchange(b.y)
        broke = kernels.dilatation_and_forces(b.y, b.row_ptr, b.nbr, b.xi_len, b.weight,
                                              b._broken_arg(), b.vol, b.m, mat.K, mat.mu, b.limits,
                                              b.nofail, b.theta, b.f, b._ws,
                                              between=self._exchange, rest=b.rest,
                                              crush_yield=b.failure.crush_yield,
                                              owned=self._owned_rows,
                                              strength=b.strength_factors, m_now=b.m_now,
                                              shear=b.shear)
        if b.rest is not None:
            b.fracture_dissipated += b._ws.crush_dissipated
        if broke == 0:  # the usual step: no recount over the bonds
            return 0
        b.fracture_dissipated += b._ledger.released(b, self.plan.owned)
        before, self._counted_broken = self._counted_broken, self._broken_count()
        return self._counted_broken - before

    # -- stepping ----------------------------------------------------------------------------
    def start(self) -> None:
        """Initial forces (call once before the first step)."""
        self.body._apply_constraints(self.body.time)
        before = self.body.fracture_dissipated
        self.refresh_forces()
        self.body.fracture_dissipated = before  # breaks before the start: not the run's

    def step(self, dt: float) -> int:
        """One velocity-Verlet step of every rank's part; bonds broken on all ranks together."""
        self.body.begin_step(dt)
        broken = self.compute_forces()
        self.body.end_step(dt)
        if broken:  # bonds that broke acted in this step; the next starts without them
            self.refresh_forces()
        return broken

    def refresh_forces(self) -> None:
        """The forces without the bonds the last pass broke, recomputed on all ranks until no
        further bond breaks anywhere."""
        while self.compute_forces():
            pass

    def update_intact_volume(self) -> None:
        """Every rank's weighted volume of the intact bonds after bonds broke, the halo's from
        its owners (collective; :mod:`pdfem.pd.failure.damaged_volume`)."""
        self.body.update_intact_volume()
        self._exchange(self.body.m_now)

    # -- the IceParticles interface (pdfem.pd.ice_interface) ----------------------------------
    # Arrays are the local ones (owned and halo particles); sums are over owned particles and
    # over all ranks, so every rank gets the same totals.
    distributed = True
    name = property(lambda self: self.body.name)
    material = property(lambda self: self.body.material)
    failure = property(lambda self: self.body.failure)
    dx = property(lambda self: self.body.dx)
    delta = property(lambda self: self.body.delta)
    s0 = property(lambda self: self.body.s0)
    x0 = property(lambda self: self.body.x0)
    vol = property(lambda self: self.body.vol)
    y = property(lambda self: self.body.y)
    v = property(lambda self: self.body.v)
    f = property(lambda self: self.body.f)
    broken = property(lambda self: self.body.broken)
    time = property(lambda self: self.body.time)
    n = property(lambda self: self.body.n, doc="Number of local (owned and halo) particles.")

    @property
    def owned(self) -> np.ndarray:
        """(n_local,) bool: the particles this rank owns (contact is resolved for these)."""
        return self.plan.owned

    @property
    def gravity(self) -> np.ndarray:
        """(3,) uniform body acceleration of the kick (m/s^2)."""
        return self.body.gravity

    @gravity.setter
    def gravity(self, value) -> None:
        self.body.gravity = value

    def begin_step(self, dt: float, keep_old: bool = False):
        return self.body.begin_step(dt, keep_old)

    def compute_forces(self) -> int:
        """Forces at the current positions (two exchanges); bonds broken on all ranks (after
        which every rank updates its weighted volume of the intact bonds)."""
        broken = int(self.comm.allreduce_sum(self._compute_forces()))
        if broken:
            self.update_intact_volume()
        return broken

    def end_step(self, dt: float) -> None:
        self.body.end_step(dt)

    def owned_sum(self, per_particle: np.ndarray):
        """Sum of a local per-particle array over the owned particles of all ranks."""
        return self.comm.allreduce_sum(per_particle[self.plan.owned].sum(axis=0))

    _sum = owned_sum

    def reactions(self) -> dict[str, np.ndarray]:
        """The reaction (N) of each fixed or prescribed region by name, summed over the owned
        particles of all ranks (each rank's constraints hold only its owned particles; one sum
        over ranks, in rank order, so every rank gets the same totals; collective)."""
        total = self.comm.allreduce_sum(reaction_forces(self.body))
        return dict(zip([c.name for c in self.body.constraints], total))

    @property
    def external_work(self) -> float:
        return float(self.comm.allreduce_sum(self.body.external_work))

    @external_work.setter
    def external_work(self, value: float) -> None:
        self.body.external_work = value if self.comm.rank == 0 else 0.0

    @property
    def fracture_dissipated(self) -> float:
        """Energy (J) released by the bonds broken since the start, all ranks (collective)."""
        return float(self.comm.allreduce_sum(self.body.fracture_dissipated))

    def kinetic_energy(self) -> float:
        b = self.body
        return 0.5 * b.material.density * float(self._sum(b.vol * np.einsum("ij,ij->i", b.v, b.v)))

    def strain_energy(self) -> float:
        b, mat = self.body, self.body.material
        theta = np.empty(len(b.vol))
        kernels.dilatation(b.y, b.row_ptr, b.nbr, b.xi_len, b.weight, b._broken_arg(), b.vol, b.m,
                           theta, b._ws)
        self._exchange(theta)
        W = kernels.strain_energy(b.y, b.row_ptr, b.nbr, b.xi_len, b.weight, b._broken_arg(), b.vol,
                                  b.m, theta, mat.K, mat.mu, b._ws)
        crushed = 0.0 if b.rest is None else kernels.contact_bond_energy(
            b.y, b.row_ptr, b.nbr, b.xi_len, b.weight, b._broken_arg(), b.rest, b.vol, b.m,
            mat.mu, owned=self.plan.owned, **shear_energy_args(b.shear))
        return float(self._sum(W * b.vol)) + float(self.comm.allreduce_sum(crushed))

    @property
    def n_bonds(self) -> int:
        """Number of bonds of the whole body (all ranks)."""
        return self.global_bonds

    def counts(self) -> tuple[int, int, int]:
        """Particles, bonds and broken bonds of the whole body (collective)."""
        broken = int(self.comm.allreduce_sum(np.int64(self._broken_count())))
        return self.global_n, self.global_bonds, broken

    def stable_time_step(self) -> float:
        """The whole body's stable step (s), as the serial body's (collective;
        :mod:`pdfem.pd.layout.timestep`)."""
        return split_stable_time_step(self.body, self.plan.owned, self._exchange, self.comm)

    def momentum(self) -> np.ndarray:
        b = self.body
        return b.material.density * self._sum(b.vol[:, None] * b.v)

    def displacement(self) -> np.ndarray:
        return self.body.displacement()

    # -- results -----------------------------------------------------------------------------
    def gather(self, values: np.ndarray) -> np.ndarray | None:
        """The owned entries of a local per-particle array, assembled in global order on rank 0
        (``None`` on the other ranks)."""
        owned = self.plan.local[self.plan.owned]
        parts = self.comm.gather((owned, np.ascontiguousarray(values[self.plan.owned])))
        if parts is None:
            return None
        out = np.empty((self.global_n,) + values.shape[1:], dtype=values.dtype)
        for idx, vals in parts:
            out[idx] = vals
        return out

    def frame_fields(self) -> dict[str, np.ndarray] | None:
        """``{"u" m, "v" m/s, "damage"}`` in global order on rank 0 (``None`` elsewhere; every
        rank must call it)."""
        u = self.gather(self.body.displacement())
        v = self.gather(self.body.v)
        d = self.gather(self.damage())
        return None if u is None else {"u": u, "v": v, "damage": d}

    def owned_reference(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Global numbers, reference positions (m) and volumes (m^3) of the owned particles."""
        own = self.owned
        return self.plan.local[own], self.x0[own], self.vol[own]

    def owned_frame_fields(self) -> dict[str, np.ndarray]:
        """``{"u", "v", "damage"}`` of the owned particles, in :meth:`owned_reference` order."""
        own = self.owned
        return {"u": self.body.displacement()[own], "v": self.body.v[own],
                "damage": self.damage()[own]}

    def damage(self) -> np.ndarray:
        """Local damage (right for owned particles)."""
        return self.body.damage()
