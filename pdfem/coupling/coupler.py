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
   step (:meth:`pdfem.fem.base.Structure.apply_surface_impulse`); a structure advanced by
   implicit steps has taken its step first, and the impulses amend it
   (:class:`pdfem.fem.surface_motion.SteppedSurface`).

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
``v . J + J^2 / (2 m)`` at the impulse's instant; for an implicit structure the trapezoidal
work ``J . (u_new - u) / dt`` of the force that amends its step, known when the impulse is
given; for a prescribed motion ``v . J``, the work its drive does); minus their sum is the
energy the contacts dissipated. Units: s, m, N, N s, J.

The coupler keeps one record per structure (:class:`StructureRecord`: its surface motion, its
pending impulse, its contact pairs, its facet loads, the contact work on it) and one per ice
body (:class:`BodyRecord`: its particle masses and global numbers, its pairs); each structure
says itself how its surface moves over a substep (:mod:`pdfem.fem.surface_motion`: predicted
or prescribed), so the coupler never asks which kind it holds. The two step variants share the
same phases: drift and contact (:meth:`Coupler._contact`), hand-over of the impulses
(:meth:`Coupler._hand_over`), their action on the structures (:meth:`Coupler._apply_impulses`)
and the end of the ice step (:meth:`Coupler._finish_ice_step`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from pdfem.coupling.contact import SurfaceContact
from pdfem.coupling.drift import drift
from pdfem.coupling.facet_loads import FacetLoads, collect_facet_loads
from pdfem.coupling.impulse_work import ImpulseWork
from pdfem.geometry.vectors import resultant
from pdfem.parallel.comm import SerialComm
from pdfem.parallel.kernels import SERIAL_BELOW_STREAMING


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


class StructureRecord:
    """What the coupler keeps for one structure: its surface motion over the substeps, the
    contact impulses pending on its surface nodes (N s), its contact pairs, its facet loads and
    the work of the contact loads on it (J)."""

    def __init__(self, structure, pairs: list[ContactPair]) -> None:
        self.structure = structure
        self.motion = structure.surface_motion()
        self.impulse = np.zeros((len(structure.surface_points()), 3))
        self.pairs = pairs
        self.facet_loads = FacetLoads(structure)
        self.contact_work = 0.0
        self.end = None  # (end positions, velocity) of the surface over the current substep


class BodyRecord:
    """What the coupler keeps for one ice body: its particle masses (kg) and global numbers
    (-1 for particles it does not own: the order in which the contacts' impulses are summed
    onto the structure), and its contact pairs."""

    def __init__(self, body, pairs: list[ContactPair]) -> None:
        self.body = body
        self.pairs = pairs
        self._work: ImpulseWork | None = None
        self.particles_moved()

    def particles_moved(self) -> None:
        """Masses and global numbers of the body's local particles, anew."""
        b = self.body
        self.mass = b.material.density * b.vol
        self.ids = np.full(len(b.v), -1, dtype=np.int64)
        self.ids[b.owned] = b.owned_reference()[0]

    def impulse_work(self) -> ImpulseWork | None:
        """The ledger of the contact impulses' work for a step starting now (None for a body
        without contact pairs): one ledger, reused step after step."""
        if not self.pairs:
            return None
        if self._work is None:
            self._work = ImpulseWork(self.body, self.mass)
        else:
            self._work.start(self.body, self.mass)
        return self._work


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
        The structures (:class:`pdfem.fem.base.Structure`), each a contact surface with
        ``step(dt)`` and a ``surface_motion()``.
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
        The communicator (:mod:`pdfem.parallel.comm`; one process: its serial stand-in): the
        contact impulses are gathered over it and summed in global particle order (the serial
        order), so every process advances the replicated structures identically. Contact is
        resolved for each body's ``owned`` particles.
    """

    def __init__(self, bodies: list, structures: list, pairs: list[ContactPair],
                 coupling_step: float, ice_substeps: int = 1, structure_substeps: int = 1,
                 forces=(), comm=SerialComm()):
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
        self.body_records = [BodyRecord(b, [p for p in self.pairs if p.body is b])
                             for b in self.bodies]
        self.records = [StructureRecord(s, [p for p in self.pairs if p.structure is s])
                        for s in self.structures]
        self.contact_work_on_ice = 0.0  # J

    def record(self, structure) -> StructureRecord:
        """The record of ``structure``."""
        return next(r for r in self.records if r.structure is structure)

    def particles_moved(self) -> None:
        """Per-particle masses (kg) and global numbers of the bodies' local particles, anew
        (after a re-partition)."""
        for r in self.body_records:
            r.particles_moved()

    @property
    def contact_dissipated(self) -> float:
        """Energy (J) lost in contacts so far: minus the work of the contact impulses on the
        ice and on the structures. The contact of Eq. (5) is perfectly plastic particle by
        particle; this loss shrinks as the ice is refined."""
        on_ice = self.comm.allreduce_sum(self.contact_work_on_ice)
        return -(on_ice + sum(r.contact_work for r in self.records))

    def checkpoint_state(self) -> dict[str, np.ndarray | float]:
        """The coupler's own state, for a checkpoint: ``time`` (s), per structure (in order)
        ``contact_work_<k>`` (J) and its facet loads
        (:meth:`pdfem.coupling.facet_loads.FacetLoads.checkpoint_state`) as
        ``facets_<k>_<key>``, ``contact_work_on_ice`` (J), and per pair (in order) ``force_<k>``
        (N), ``moment_<k>`` (N m), ``contacts_<k>`` and ``total_impulse_<k>`` (N s).

        Every process must call it: the counters each keeps for its own particles (contact
        work on the ice, total impulses) are summed over the processes, and each one's part is
        kept in ``<key>_ranks`` so that a restart on as many ranks continues bit for bit."""
        out: dict[str, np.ndarray | float] = {"time": self.time,
                                              "contact_work_on_ice": self.contact_work_on_ice}
        for k, r in enumerate(self.records):
            out[f"contact_work_{k}"] = r.contact_work
            for key, v in r.facet_loads.checkpoint_state().items():
                out[f"facets_{k}_{key}"] = v
        for k, p in enumerate(self.pairs):
            out[f"force_{k}"] = p.force.copy()
            out[f"moment_{k}"] = p.moment.copy()
            out[f"contacts_{k}"] = p.contacts
            out[f"total_impulse_{k}"] = p.contact.total_impulse.copy()
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
        rank, size = self.comm.rank, self.comm.size
        for key in self._rank_local_keys():
            parts = state.get(f"{key}_ranks")
            if parts is not None and len(parts) == size:
                state[key] = parts[rank]
            elif rank != 0:
                state[key] = np.zeros_like(np.asarray(state[key], dtype=np.float64))
        self.time = float(state["time"])
        self.contact_work_on_ice = float(state["contact_work_on_ice"])
        for k, r in enumerate(self.records):
            r.contact_work = float(state[f"contact_work_{k}"])
            prefix = f"facets_{k}_"
            facets = {key[len(prefix):]: v for key, v in state.items() if key.startswith(prefix)}
            if facets:  # (a checkpoint written before the facet loads existed has none)
                r.facet_loads.restore_state(facets)
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
        for r in self.records:
            r.impulse[:] = 0.0
        for p in self.pairs:
            p.contacts = 0
        pair_impulse = [np.zeros_like(self.record(p.structure).impulse) for p in self.pairs]
        if self.ice_substeps == 1:
            broken = self._step_with_structure_substeps(pair_impulse)
        else:
            broken = self._step_with_ice_substeps(pair_impulse)
        D = self.dt
        for p, impulse in zip(self.pairs, pair_impulse):
            p.contacts = int(self.comm.allreduce_sum(p.contacts))
            force, moment = resultant(p.structure.surface_points(), impulse)
            p.force, p.moment = force / D, moment / D
        collect_facet_loads(self.records, D)
        self.time += D
        return broken

    def _set_surfaces(self, starts: dict, normals: bool = True) -> None:
        """Every pair's contact meets its structure's surface of the current substep (its
        record's ``end``, from ``starts[id(structure)]``)."""
        for p in self.pairs:
            r = self.record(p.structure)
            if normals:
                p.contact.set_surface(*r.end, start=starts[id(r)])
            else:
                p.contact.set_surface(*r.end, normals=False, start=starts[id(r)])

    def _contact(self, rec: BodyRecord, y_old, u, h: float, work, t_sub: float) -> None:
        """Resolve the contacts of body ``rec`` that drifted from ``y_old`` with the velocity
        ``u`` over ``h`` (s); their impulses go into the pairs and the work ledger ``work``;
        with ``u`` other than the body's ``v``, the impulses also change ``v``."""
        body = rec.body
        for p in rec.pairs:
            c = p.contact.resolve(body.y, y_old, u, rec.mass, h, active=body.owned,
                                  ids=rec.ids)
            p.contacts += c.contacts
            work.add(c.rows, c.row_impulse, t_sub)
            if u is not body.v:
                body.v[c.rows] += c.row_impulse / rec.mass[c.rows, None]

    def _step_with_structure_substeps(self, pair_impulse: list) -> int:
        """One ice step of D whose drift is taken in the structures' substeps: before each
        structure substep the particles drift over it and meet each surface as its structure
        says it moves (predicted from its state at the substep's start, or prescribed), and
        the impulses act on both at that instant (the ice's bond forces stay those of the
        step's start)."""
        D, n = self.dt, self.structure_substeps
        h = D / n
        # the impulse ledgers of the bodies in contact pairs (a body without pairs takes none)
        works = [r.impulse_work() for r in self.body_records]
        v0 = [None if n == 1 else w.v0 if w is not None else b.v.copy()
              for w, b in zip(works, self.bodies)]
        for b in self.bodies:
            b.begin_step(D, drift=False)         # the drift is taken below, in n parts
        # the first half kick, D/2 a_t (with n substeps), and the drift's buffers: the
        # positions before each substep's move (for the contact) and its velocity
        kicks = [None if v is None else b.v - v for b, v in zip(self.bodies, v0)]
        befores = [None if w is None else np.empty_like(b.y) for w, b in zip(works, self.bodies)]
        us = [b.v if k is None else np.empty_like(b.v) for k, b in zip(kicks, self.bodies)]
        for j in range(n):
            starts = {}
            for r in self.records:
                p0, end, velocity = r.motion.over(h)
                starts[id(r)], r.end = p0, (end, velocity)
            self._set_surfaces(starts, normals=j == 0)
            for rec, work, kick, before, u in zip(self.body_records, works, kicks, befores, us):
                body = rec.body
                # the velocity of substep j: v_t + a_t (j + 1/2) h, so that a contact stops
                # the particle's velocity of that instant (not the mid-step velocity of the
                # whole step, off by O(D a)); the positions at the step's end are Verlet's.
                # The body keeps its arrays (in place).
                drift(len(body.y) >= SERIAL_BELOW_STREAMING, body.y, body.v,
                      body.v if kick is None else kick, (2 * j + 1) / n - 1.0, h,
                      body.y if before is None else before, u, kick is not None,
                      before is not None)
                if work is not None:
                    self._contact(rec, before, u, h, work, j * h)
            self._hand_over(pair_impulse)
            self._apply_impulses()
            for r in self.records:
                r.motion.after(h)
        broken = self._finish_ice_step(D)
        self.contact_work_on_ice += sum(w.work(b) for w, b in zip(works, self.bodies)
                                        if w is not None)
        self._after_breaking(broken)
        return broken

    def _step_with_ice_substeps(self, pair_impulse: list) -> int:
        """``ice_substeps`` ice steps against the structures' surfaces as each says it moves
        over the coupling step (predicted from its state at each substep's start, or
        prescribed); the impulses of each ice step act on the structures at once, and they
        move on with that velocity; then one structure step."""
        D = self.dt
        h = D / self.ice_substeps
        for r in self.records:
            r.motion.begin(D)
        broken = 0
        for k in range(self.ice_substeps):
            frac = (k + 1) / self.ice_substeps
            starts = {}
            for r in self.records:
                start, end, velocity = r.motion.sample(h, frac)
                starts[id(r)], r.end = start, (end, velocity)
            self._set_surfaces(starts)
            works = [r.impulse_work() for r in self.body_records]
            olds = [r.body.begin_step(h, keep_old=bool(r.pairs)) for r in self.body_records]
            for rec, y_old, work in zip(self.body_records, olds, works):
                if work is not None:
                    self._contact(rec, y_old, rec.body.v, h, work, 0.0)
            self._hand_over(pair_impulse)
            self._apply_impulses()
            now = self._finish_ice_step(h)
            self.contact_work_on_ice += sum(w.work(b) for w, b in zip(works, self.bodies)
                                        if w is not None)
            self._after_breaking(now)
            broken += now
        for r in self.records:
            r.motion.after(D)
        return broken

    def _apply_impulses(self) -> None:
        """Give each structure its pending impulses now (a velocity jump of a structure that
        responds; nothing for a prescribed motion) and book their work."""
        for r in self.records:
            if r.impulse.any():
                r.contact_work += r.motion.respond(r.impulse)
                r.impulse[:] = 0.0

    def _hand_over(self, pair_impulse: list) -> None:
        """Take the impulses of the contacts just resolved (summed over ranks) into the pairs'
        totals and the structures' pending impulses; book the work of prescribed motions (at
        their surface velocity of the substep)."""
        for p, total in zip(self.pairs, pair_impulse):
            r = self.record(p.structure)
            impulse = p.contact.take_impulse(self.comm.allgather)
            r.contact_work += r.motion.drive_work(impulse, r.end[1])
            r.impulse += impulse
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
        ps = self.record(structure).pairs
        return (sum((p.force for p in ps), np.zeros(3)), sum((p.moment for p in ps), np.zeros(3)),
                sum(p.contacts for p in ps))
