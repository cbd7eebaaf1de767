"""The coupled time step: ice bodies and structures advanced together, with subcycling.

One coupling step of length ``D`` (the larger of the ice and structure steps):

1. every structure takes ``structure_substeps`` steps of ``D / structure_substeps`` under its
   own loads, its contact surface moving from ``p0`` to ``p1`` and its surface velocity going
   from ``v0`` to ``v1``;
2. every ice body takes ``ice_substeps`` velocity-Verlet steps of ``D / ice_substeps``; after
   each position update the particles that crossed a structure's surface are put back on it
   and particle and surface exchange a plastic impulse computed with both masses
   (:class:`pdfem.coupling.contact.SurfaceContact`). The surface is taken at that substep's
   time by linear interpolation between ``p0`` and ``p1`` (``v0`` and ``v1``), plus the
   velocity the impulses of the earlier substeps gave it;
3. the impulses are applied to the structures as a velocity jump at the end of the coupling
   step (:meth:`pdfem.fem.base.Structure.apply_surface_impulse`).

One of the two substep counts is 1: the faster side subcycles. When the structure subcycles
(one ice step per coupling step) the ice meets the structure's surface at the very instant the
structure has reached, with its actual node velocities, and the impulse acts on both sides at
that instant: no lag. The ice's drift over the step is taken in the structure's substeps, in
substep ``j`` with the velocity ``v_t + a_t (j + 1/2) h`` (``h = D / n``): the half kick of
velocity Verlet spread over the substeps, which leaves the step's end positions and velocities
Verlet's. A contact then stops the particle's velocity of that substep; with Verlet's
mid-step velocity ``v_t + a_t D / 2`` instead, the velocity the impulse stopped was off by
up to ``a_t D / 2`` from the one the energy balance sees (:mod:`pdfem.coupling.impulse_work`),
and ice pressed on the surface by its neighbours gained energy in the contacts at the
largest steps (the demo at safety 0.9: -0.8 % of the input) and loaded a subcycled structure
5-7 % above the small-step run.
When the ice subcycles, the surface between structure steps is interpolated and the impulses
reach the structure at the end of the step, at most one (structure-stable) step late.

Momentum: the impulse that leaves the ice reaches the structure exactly, in the same coupling
step, so the total momentum of ice and structures is conserved to round-off when nothing else
acts. Energy: the coupler keeps the work of the contact impulses on the ice (at the velocity
the particles hit the surface with) and on each structure (its kinetic-energy change
``v . J + J^2 / (2 m)`` at the impulse's instant; for a prescribed motion ``v . J``, the work
its drive does); minus their sum is the energy the contacts dissipated. Units: s, m, N, N s, J.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from pdfem.coupling.contact import SurfaceContact
from pdfem.coupling.facet_loads import FacetLoads, collect_facet_loads
from pdfem.coupling.impulse_work import ImpulseWork


@dataclass
class ContactPair:
    """An ice body, a structure and the contact between them, with its load record."""

    name: str
    body: object                 # pdfem.pd.ice_interface.IceParticles
    structure: object            # a pdfem.fem.surface.ContactSurface
    contact: SurfaceContact
    force: np.ndarray = field(default_factory=lambda: np.zeros(3))    # N, last coupling step
    moment: np.ndarray = field(default_factory=lambda: np.zeros(3))   # N m about the origin
    contacts: int = 0            # particle contacts in the last coupling step


def _global_numbers(body) -> np.ndarray:
    """(N,) global particle numbers of a body's local particles (-1 for those it does not own):
    the order in which the contacts' impulses are summed onto the structure."""
    ids = np.full(len(body.v), -1, dtype=np.int64)
    ids[body.owned] = body.owned_reference()[0]
    return ids


def substep_counts(ice_step: float, structure_step: float, substeps: int = 0):
    """Coupling step and substep counts from the two stable steps (s).

    Parameters
    ----------
    ice_step, structure_step
        Largest usable step of the ice and of the structures (``inf`` if there are none).
    substeps
        Substeps of the faster side per coupling step; 0 chooses the most that keep the
        slower side at its own step.

    Returns
    -------
    (coupling_step, ice_substeps, structure_substeps)
    """
    if not math.isfinite(structure_step):
        return ice_step, 1, 1
    if not math.isfinite(ice_step):
        return structure_step, 1, 1
    fast, slow = sorted((ice_step, structure_step))
    n = max(1, math.floor(slow / fast * (1 + 1e-12))) if substeps == 0 else substeps
    coupling = min(slow, n * fast)
    if ice_step <= structure_step:
        return coupling, n, 1
    return coupling, 1, n


class Coupler:
    """Advance ice bodies and structures together (see the module docstring).

    Parameters
    ----------
    bodies
        The ice bodies (:class:`pdfem.pd.ice_interface.IceParticles`: ``begin_step``,
        ``compute_forces``, ``end_step``, ``y``, ``v``, ``f``, ``vol``, ``material.density``,
        ``gravity``, ``owned``).
    structures
        The structures (elastic or rigid), each a contact surface with ``step(dt)``.
    pairs
        The contact pairs.
    coupling_step
        D (s).
    ice_substeps, structure_substeps
        Steps per coupling step of each side.
    forces
        Particle forces other than the bonds (:class:`pdfem.forces.base.ParticleForce`, e.g.
        gravity and short-range contact between ice particles): after the bond forces of each
        ice step, each adds its force density to the bodies' ``f``, in list order.
    comm
        With ice bodies split over MPI ranks (:class:`pdfem.pd.layout.halo.DistributedIce`):
        the communicator over which the contact impulses are gathered and summed in global
        particle order (the serial order), so every rank advances the replicated structures
        identically and as the serial run does. Contact
        is resolved for each body's ``owned`` particles (all of them for a whole body).
    """

    def __init__(self, bodies: list, structures: list, pairs: list[ContactPair],
                 coupling_step: float, ice_substeps: int = 1, structure_substeps: int = 1,
                 forces=(), comm=None):
        if ice_substeps < 1 or structure_substeps < 1:
            raise ValueError("substep counts must be >= 1")
        self.bodies = list(bodies)
        self.structures = list(structures)
        self.pairs = list(pairs)
        self.dt = float(coupling_step)
        self.ice_substeps = int(ice_substeps)
        self.structure_substeps = int(structure_substeps)
        self.forces = list(forces)
        self.comm, self.time = comm, 0.0
        self._pairs_of = {id(b): [p for p in self.pairs if p.body is b] for b in self.bodies}
        self.particles_moved()
        # N s, contact impulses on each structure's surface nodes in the current coupling step
        self._impulse = {id(s): np.zeros((len(s.surface_points()), 3)) for s in self.structures}
        # J, work of the contact loads on each structure (as it moves under them)
        self.contact_work = {id(s): 0.0 for s in self.structures}
        self.contact_work_on_ice = 0.0  # J
        # per structure: contact loads per facet of its surface (pressure, load patches)
        self.facet_loads = {id(s): FacetLoads(s) for s in self.structures}

    def particles_moved(self) -> None:
        """Per-particle masses (kg) and global numbers of the bodies' local particles, anew."""
        self._mass = {id(b): b.material.density * b.vol for b in self.bodies}
        self._ids = {id(b): _global_numbers(b) for b in self.bodies}

    @property
    def contact_dissipated(self) -> float:
        """Energy (J) lost in contacts so far: minus the work of the contact impulses on the
        ice and on the structures. The contact of Eq. (5) is perfectly plastic particle by
        particle; this loss shrinks as the ice is refined."""
        on_ice = self.contact_work_on_ice
        if self.comm is not None:
            on_ice = self.comm.allreduce_sum(on_ice)
        return -(on_ice + sum(self.contact_work.values()))

    def checkpoint_state(self) -> dict[str, np.ndarray | float]:
        """The coupler's own state, for a checkpoint: ``time`` (s), per structure (in order)
        ``load_<k>`` (the pending contact load, N per surface node) and ``contact_work_<k>``
        (J), ``contact_work_on_ice`` (J), and per pair (in order) ``force_<k>`` (N),
        ``moment_<k>`` (N m), ``contacts_<k>`` and ``total_impulse_<k>`` (N s); per structure
        its facet loads (:meth:`pdfem.coupling.facet_loads.FacetLoads.checkpoint_state`) as
        ``facets_<k>_<key>``.

        With a communicator (ice split over ranks) every rank must call it: the counters each
        rank keeps for its own particles (contact work on the ice, total impulses) are summed
        over ranks, and each rank's part is kept in ``<key>_ranks`` so that a restart on as
        many ranks continues bit for bit."""
        out: dict[str, np.ndarray | float] = {"time": self.time,
                                              "contact_work_on_ice": self.contact_work_on_ice}
        for k, s in enumerate(self.structures):
            out[f"contact_work_{k}"] = self.contact_work[id(s)]
            for key, v in self.facet_loads[id(s)].checkpoint_state().items():
                out[f"facets_{k}_{key}"] = v
        for k, p in enumerate(self.pairs):
            out[f"force_{k}"] = p.force.copy()
            out[f"moment_{k}"] = p.moment.copy()
            out[f"contacts_{k}"] = p.contacts
            out[f"total_impulse_{k}"] = p.contact.total_impulse.copy()
        if self.comm is not None:
            for key in self._rank_local_keys():
                parts = self.comm.gather(out[key])
                out[key] = self.comm.allreduce_sum(out[key])
                if parts is not None:
                    out[f"{key}_ranks"] = np.array(parts)
        return out

    def _rank_local_keys(self) -> list[str]:
        """State keys whose values each rank keeps for its own ice particles."""
        return ["contact_work_on_ice"] + [f"total_impulse_{k}" for k in range(len(self.pairs))]

    def restore_state(self, state: dict) -> None:
        """Restore a state from :meth:`checkpoint_state` exactly (same structures and pairs, same
        order). A state written on another number of ranks gives rank 0 the totals."""
        state = dict(state)
        rank, size = (0, 1) if self.comm is None else (self.comm.rank, self.comm.size)
        for key in self._rank_local_keys():
            parts = state.get(f"{key}_ranks")
            if parts is not None and len(parts) == size:
                state[key] = parts[rank]
            elif rank != 0:
                state[key] = np.zeros_like(np.asarray(state[key], dtype=np.float64))
        self.time = float(state["time"])
        self.contact_work_on_ice = float(state["contact_work_on_ice"])
        for k, s in enumerate(self.structures):
            self.contact_work[id(s)] = float(state[f"contact_work_{k}"])
            prefix = f"facets_{k}_"
            facets = {key[len(prefix):]: v for key, v in state.items() if key.startswith(prefix)}
            if facets:  # (a checkpoint written before the facet loads existed has none)
                self.facet_loads[id(s)].restore_state(facets)
        for k, p in enumerate(self.pairs):
            p.force = np.array(state[f"force_{k}"], dtype=np.float64)
            p.moment = np.array(state[f"moment_{k}"], dtype=np.float64)
            p.contacts = int(state[f"contacts_{k}"])
            p.contact.total_impulse[:] = state[f"total_impulse_{k}"]

    def start(self) -> None:
        """Initial forces of the ice (call once before the first step)."""
        for b in self.bodies:
            b.start()
        for force in self.forces:
            force.add_forces()

    def step(self) -> int:
        """Advance everything by one coupling step; return the number of bonds broken."""
        for s in self.structures:
            self._impulse[id(s)][:] = 0.0
        for p in self.pairs:
            p.contacts = 0
        pair_impulse = [np.zeros_like(self._impulse[id(p.structure)]) for p in self.pairs]
        if self.ice_substeps == 1:
            broken = self._step_with_structure_substeps(pair_impulse)
        else:
            broken = self._step_with_ice_substeps(pair_impulse)
        D = self.dt
        for p, impulse in zip(self.pairs, pair_impulse):
            if self.comm is not None:
                p.contacts = int(self.comm.allreduce_sum(p.contacts))
            p.force = impulse.sum(axis=0) / D
            p.moment = np.cross(p.structure.surface_points(), impulse).sum(axis=0) / D
        collect_facet_loads(self.facet_loads, self.pairs, D)
        self.time += D
        return broken

    def _step_with_structure_substeps(self, pair_impulse: list) -> int:
        """One ice step of D whose drift is taken in the structures' substeps: before each
        structure substep the particles drift over it and meet the surface predicted from the
        structure's state at the substep's start, and the impulses act on both at that
        instant (the ice's bond forces stay those of the step's start)."""
        D, n = self.dt, self.structure_substeps
        h = D / n
        works = [ImpulseWork(b) for b in self.bodies]
        olds = [b.begin_step(D, keep_old=True) for b in self.bodies]
        kicks = {}
        for b, y_old, work in zip(self.bodies, olds, works):
            b.y[:] = y_old                       # the drift is taken below, in n parts
            kicks[id(b)] = b.v - work.v0         # the first half kick, D/2 a_t
        for j in range(n):
            ends, starts = {}, {}
            for s in self.structures:
                p0 = s.surface_points().copy()
                starts[id(s)] = p0
                if s.prescribed_motion:          # known motion: the substep is taken first
                    s.step(h)
                    ends[id(s)] = (s.surface_points().copy(), (s.surface_points() - p0) / h)
                else:                            # predicted from its state now
                    v0 = s.surface_velocities().copy()
                    ends[id(s)] = (p0 + h * v0, v0)
            for p in self.pairs:
                p.contact.set_surface(*ends[id(p.structure)], normals=j == 0,
                                      start=starts[id(p.structure)])
            for body, work in zip(self.bodies, works):
                y = body.y                       # in place: the body keeps its array
                before = y.copy()
                # the velocity of substep j: v_t + a_t (j + 1/2) h, so that a contact stops
                # the particle's velocity of that instant (not the mid-step velocity of the
                # whole step, off by O(D a)); the positions at the step's end are Verlet's
                u = body.v if n == 1 else body.v + kicks[id(body)] * ((2 * j + 1) / n - 1.0)
                y += h * u
                for p in self._pairs_of[id(body)]:
                    m = self._mass[id(body)]
                    c = p.contact.resolve(body.y, before, u, m, h, active=body.owned,
                                          ids=self._ids[id(body)])
                    p.contacts += c.contacts
                    work.add(c.particle_impulse, j * h)
                    if u is not body.v:
                        np.add(body.v, c.particle_impulse / m[:, None], out=body.v)
            self._hand_over(pair_impulse, {k: e[1] for k, e in ends.items()})
            self._apply_impulses()
            for s in self.structures:
                if not s.prescribed_motion:
                    s.step(h)
        broken = self._finish_ice_step(D)
        self.contact_work_on_ice += sum(w.work(b) for w, b in zip(works, self.bodies))
        self._after_breaking(broken)
        return broken

    def _step_with_ice_substeps(self, pair_impulse: list) -> int:
        """``ice_substeps`` ice steps against the structures' surfaces predicted from their
        state at the coupling step's start (prescribed motions: taken); the impulses of each
        ice step act on the structures at once, at the coupling step's start, and they move
        on with that velocity; then one structure step."""
        D = self.dt
        h = D / self.ice_substeps
        known, pos = {}, {}
        for s in self.structures:
            pos[id(s)] = s.surface_points().copy()
            if s.prescribed_motion:
                s.step(D)
                known[id(s)] = (pos[id(s)], s.surface_points() - pos[id(s)])
        broken = 0
        for k in range(self.ice_substeps):
            frac = (k + 1) / self.ice_substeps
            ends, starts = {}, dict(pos)
            for s in self.structures:
                if s.prescribed_motion:
                    p0, dp = known[id(s)]
                    ends[id(s)] = (p0 + frac * dp, dp / D)
                else:
                    v = s.surface_velocities().copy()
                    ends[id(s)] = (pos[id(s)] + h * v, v)
                pos[id(s)] = ends[id(s)][0]
            for p in self.pairs:
                p.contact.set_surface(*ends[id(p.structure)], start=starts[id(p.structure)])
            works = [ImpulseWork(b) for b in self.bodies]
            olds = [b.begin_step(h, keep_old=True) for b in self.bodies]
            for body, y_old, work in zip(self.bodies, olds, works):
                for p in self._pairs_of[id(body)]:
                    c = p.contact.resolve(body.y, y_old, body.v, self._mass[id(body)], h,
                                          active=body.owned, ids=self._ids[id(body)])
                    p.contacts += c.contacts
                    work.add(c.particle_impulse, 0.0)
            self._hand_over(pair_impulse, {key: e[1] for key, e in ends.items()})
            self._apply_impulses()
            now = self._finish_ice_step(h)
            self.contact_work_on_ice += sum(w.work(b) for w, b in zip(works, self.bodies))
            self._after_breaking(now)
            broken += now
        for s in self.structures:
            if not s.prescribed_motion:
                s.step(D)
        return broken

    def _apply_impulses(self) -> None:
        """Give each responding structure its pending impulses now (a velocity jump) and book
        their work."""
        for s in self.structures:
            if not s.prescribed_motion and self._impulse[id(s)].any():
                self.contact_work[id(s)] += s.apply_surface_impulse(self._impulse[id(s)])
                self._impulse[id(s)][:] = 0.0

    def _hand_over(self, pair_impulse: list, velocity: dict) -> None:
        """Take the impulses of the contacts just resolved (summed over ranks) into the pairs'
        totals and the structures' pending impulses; book the work of prescribed motions (at
        their surface velocity ``velocity``)."""
        for p, total in zip(self.pairs, pair_impulse):
            k = id(p.structure)
            impulse = p.contact.take_impulse(None if self.comm is None else self.comm.allgather)
            if p.structure.prescribed_motion:
                self.contact_work[k] += float(np.sum(impulse * velocity[k]))
            self._impulse[k] += impulse
            total += impulse

    def _after_breaking(self, broken: int) -> None:
        """After a step in which bonds broke: the forces again, without them, for the next
        step's first half kick. A bond that breaks at the step's end still acted in that step
        (both half kicks around it used its force), so the integrator's work matches the
        energy balance, and the energy it held leaves with it (the fracture term)."""
        if broken:
            for b in self.bodies:
                b.refresh_forces()
            for force in self.forces:
                force.add_forces()

    def _finish_ice_step(self, h: float) -> int:
        """Bond forces at the new positions, the particle forces, the second half kick; bonds
        broken."""
        broken = sum(b.compute_forces() for b in self.bodies)
        for force in self.forces:
            force.add_forces()
        for b in self.bodies:
            b.end_step(h)
        return broken

    def structure_load(self, structure) -> tuple[np.ndarray, np.ndarray, int]:
        """Force (N), moment (N m, about the origin) and particle contacts of the last coupling
        step on ``structure``, summed over its contact pairs."""
        ps = [p for p in self.pairs if p.structure is structure]
        return (sum((p.force for p in ps), np.zeros(3)), sum((p.moment for p in ps), np.zeros(3)),
                sum(p.contacts for p in ps))
