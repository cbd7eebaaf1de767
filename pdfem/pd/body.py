"""An ice body: particles, bonds and state arrays, advanced by velocity-Verlet steps.

One class for a body held whole by one process and for one MPI rank's part of a body split
over ranks: the arrays are always the *local* ones (the particles this process holds, in global
order, and their bonds), and whatever crosses processes goes through the body's
:mod:`layout <pdfem.pd.layout.base>` (halo exchanges, sums over owned particles, gathers): a
:class:`~pdfem.pd.layout.base.WholeLayout` for a whole body, a
:class:`~pdfem.pd.layout.halo.HaloLayout` for a rank's part. The physics never asks which.

The class holds flat arrays and calls the numba kernels of :mod:`pdfem.pd.bonds.kernels` (no
loops of its own). Particles are numbered in cell order, so bond partners sit close in memory.
Bonds cost 16 bytes each (:class:`pdfem.pd.bonds.data.Bonds`: int32 partner, float64 reference
length, float32 weight whose sign marks a broken bond). Which bonds break is the body's failure
law's decision (:mod:`pdfem.pd.failure`; default: the material's critical stretch). The strain
energy that breaking bonds take with them is counted in ``fracture_dissipated``
(:mod:`pdfem.pd.failure.fracture`). Builders: :meth:`IceBody.from_shape` (a lattice-filled
shape, whole or a rank's part), :meth:`IceBody.from_points` (a whole body from a point cloud),
:func:`pdfem.pd.layout.split.split_body` (a rank's part of a whole body).

One step (:meth:`IceBody.step`), with force density f (N/m^3) and density rho (kg/m^3)::

    v += dt/2 (f/rho + g)        kick
    v = prescribed on constrained particles
    y += dt v                    drift
    exchange y; theta(y); exchange theta; f(y, theta)   dilatation, forces, bond breaking
    v += dt/2 (f/rho + g)        kick
    v = prescribed on constrained particles

with g the uniform body acceleration ``gravity`` (set by :class:`pdfem.forces.gravity.Gravity`).
"""

from __future__ import annotations

import numpy as np

from pdfem.parallel.comm import SerialComm
from pdfem.pd import diagnostics
from pdfem.pd.bonds import kernels
from pdfem.pd.bonds.data import Bonds
from pdfem.pd.bonds.family import build_family
from pdfem.pd.bonds.geometry import bond_lengths, cut_crack
from pdfem.pd.bonds.influence import bond_weights, isotropy_gain
from pdfem.pd.bonds.pair_loop import SIGNED
from pdfem.pd.bonds.search import cell_pairs
from pdfem.pd.bonds.surface import surface_corrected_weights
from pdfem.pd.checkpoint import state as checkpoint
from pdfem.pd.constraints import VelocityConstraint, applied_forces, next_name, step_work
from pdfem.pd.constraints import reaction_forces
from pdfem.pd.failure import CriticalStretch, FailureLaw
from pdfem.pd.failure.crushed_shear import CrushedShear
from pdfem.pd.failure.damaged_volume import IntactVolume
from pdfem.pd.failure.fracture import FractureLedger
from pdfem.pd.failure.strain_rate import RateTracker
from pdfem.pd.integrate import set_rows, verlet_kick
from pdfem.pd.layout import rebalance as balance
from pdfem.pd.layout.base import Layout, WholeLayout
from pdfem.pd.layout.blocks import layout_workspace
from pdfem.pd.layout.setup import lattice_part
from pdfem.pd.materials.lps import IceMaterial
from pdfem.pd.timestep import body_stable_time_step

LOOPS = ("pairs", "full_family")
"""The force loops: the particle-pair loop, and the per-particle full-family reference loop."""
_REST = np.zeros(3)  # the velocity of held particles (read-only by convention)


class IceBody:
    """State of one peridynamic ice body, or of one rank's part of it (SI units).

    Parameters
    ----------
    name
        Body name (used in results).
    x0
        (n, 3) reference positions of the local particles (m), in global (cell) order.
    vol
        (n,) particle volumes (m^3).
    material
        The ice material.
    dx, delta
        Lattice spacing and horizon (m).
    bonds
        The local bonds (:class:`~pdfem.pd.bonds.data.Bonds`), in global order: every bond of
        an owned particle is here.
    m
        (n,) weighted volumes of all initial bonds (m^5), right for every local particle.
    layout
        The :class:`~pdfem.pd.layout.base.Layout` (default: the whole body on this process).
    loop
        ``"pairs"`` (the particle-pair loop) or ``"full_family"`` (the reference loop).
    failure
        The failure law (default: the critical stretch of ``material`` at ``delta``).
    influence_gain
        Gain g of the cubic influence function the weights were made with (0: w = 1).
    nofail, fixed
        (n,) uint8 no-fail flags and bool fixed flags (default: none).
    state
        Optional state arrays by name (``y``, ``v``, ``f``, ``theta``, ``rest``, ``shear``,
        ``rates``, ``constraints``, ``time``, ``gravity``), e.g. of particles moved from
        another rank; the rest starts at rest in the reference state.
    keep_bond_length
        Keep the bond lengths between the passes of a step (8 bytes per bond, saves a square
        root per bond; :class:`~pdfem.pd.bonds.workspace.PairWorkspace`).

    Raises
    ------
    ValueError
        For an unknown ``loop``, or a failure law that needs the pair loop.
    """

    def __init__(self, name: str, x0: np.ndarray, vol: np.ndarray, material: IceMaterial,
                 dx: float, delta: float, bonds: Bonds, m: np.ndarray, *,
                 layout: Layout | None = None, loop: str = "pairs",
                 failure: FailureLaw | None = None, influence_gain: float = 0.0,
                 nofail: np.ndarray | None = None, fixed: np.ndarray | None = None,
                 state: dict | None = None, keep_bond_length: bool = True) -> None:
        if loop not in LOOPS:
            raise ValueError(f"unknown PD loop {loop!r}; valid: 'pairs', 'full_family'")
        s = dict(state or {})
        n = x0.shape[0]
        self.name = name
        self.material = material
        self.dx, self.delta = float(dx), float(delta)
        self.x0, self.vol, self.m = x0, vol, m
        self.bonds = bonds
        self.layout: Layout = WholeLayout(n) if layout is None else layout
        self.loop = loop
        self.influence_gain = float(influence_gain)
        self.failure = failure or CriticalStretch.from_material(material, self.delta)
        self.nofail = np.zeros(n, dtype=np.uint8) if nofail is None else nofail
        self.fixed = np.zeros(n, dtype=bool) if fixed is None else fixed
        self._fixed_rows = (self.fixed, np.flatnonzero(self.fixed))  # (the mask, its rows)
        self.y = s.get("y", x0.copy())
        self.v = s.get("v", np.zeros_like(x0))
        self.f = s.get("f", np.zeros_like(x0))
        self.theta = s.get("theta", np.zeros(n))
        self.gravity = np.asarray(s.get("gravity", np.zeros(3)), dtype=np.float64)
        self.constraints: list[VelocityConstraint] = list(s.get("constraints", ()))
        self.time = float(s.get("time", 0.0))
        law = self.failure
        if law.broken_bonds_push and loop != "pairs":
            raise ValueError(f"the {law.name!r} failure law needs the pair loop "
                             "(pd_loop = \"pairs\")")
        self.rest = s.get("rest", np.full(bonds.n_bonds, np.nan, dtype=np.float32)
                          if law.broken_bonds_push else None)
        self.shear = s.get("shear", CrushedShear.for_bonds(bonds.n_bonds, law.crush_friction)
                           if law.crush_friction > 0.0 else None)
        self.rates = s.get("rates", RateTracker(law, material.poisson_ratio)
                           if law.rate_dependent else None)
        self.workspace = layout_workspace(bonds.row_ptr, bonds.nbr, self.layout,
                                          keep_bond_length)
        self.family = build_family(bonds.row_ptr, bonds.nbr, n) if loop == "full_family" \
            else None
        self.local_external_work = 0.0  # J, this process's part
        self.local_fracture_dissipated = 0.0  # J, this process's part (its owned particles)
        self.ledger = FractureLedger()
        self.intact = IntactVolume(m, self.layout.gid)
        self._force0: np.ndarray | None = None
        self.n_bonds = int(self.layout.allsum(np.int64(self.counted_bonds().sum())))
        self.update_intact_volume()

    @classmethod
    def from_points(cls, name: str, x: np.ndarray, material: IceMaterial, dx: float,
                    delta: float, *, loop: str = "pairs", volume: np.ndarray | None = None,
                    isotropic: bool = False, surface_correction: bool = False,
                    failure: FailureLaw | None = None, keep_bond_length: bool = True
                    ) -> "IceBody":
        """A whole body from particle positions: cell-sorted, bonded, weighted, at rest.

        Parameters
        ----------
        name, material, dx, delta, loop, failure, keep_bond_length
            As in :class:`IceBody`.
        x
            (N, 3) particle positions, m; renumbered into cell order.
        volume
            Optional (N,) particle volumes, m^3, in the order of ``x`` (default dx^3).
        isotropic
            Weigh the bonds with the cubic influence function that makes a cubic lattice of
            spacing ``dx`` aligned with the axes isotropic
            (:func:`pdfem.pd.bonds.influence.isotropy_gain`); only right for such lattices.
            False: w = 1.
        surface_correction
            Correct the bond weights so that every family's second moment is isotropic
            (:func:`pdfem.pd.bonds.surface.surface_corrected_weights`).

        Raises
        ------
        ValueError
            For an unknown ``loop``, or ``isotropic`` with a horizon too small for it.
        """
        gain = isotropy_gain(delta / dx) if isotropic else 0.0
        x = np.ascontiguousarray(x, dtype=np.float64)
        perm, row_ptr, nbr = cell_pairs(x, delta)
        x0 = np.ascontiguousarray(x[perm])
        n = x0.shape[0]
        vol = (np.full(n, dx ** 3) if volume is None
               else np.ascontiguousarray(np.asarray(volume, dtype=np.float64)[perm]))
        xi_len = bond_lengths(x0, row_ptr, nbr)
        weight = bond_weights(x0, row_ptr, nbr, xi_len, delta, dx, gain)
        layout = WholeLayout(n)
        ws = layout_workspace(row_ptr, nbr, layout, keep_bond_length=False)
        if surface_correction:
            surface_corrected_weights(x0, row_ptr, nbr, xi_len, weight, vol, ws=ws, out=weight)
        m = kernels.weighted_volume(row_ptr, nbr, xi_len, weight, vol, ws)
        return cls(name, x0, vol, material, dx, delta, Bonds(row_ptr, nbr, xi_len, weight), m,
                   layout=layout, loop=loop, failure=failure, influence_gain=gain,
                   keep_bond_length=keep_bond_length)

    @classmethod
    def from_shape(cls, name: str, shape, material: IceMaterial, dx: float, delta: float, *,
                   comm=SerialComm(), loop: str = "pairs", failure: FailureLaw | None = None,
                   isotropic: bool = True, surface_correction: bool = True,
                   keep_bond_length: bool = True) -> "IceBody":
        """The body filling ``shape`` (a :mod:`pdfem.geometry.shapes` object) with a cubic
        lattice of spacing ``dx``, as this process holds it: the whole body on one process,
        else the rank's part, built without the whole body (:func:`pdfem.pd.layout.setup.
        lattice_part`; collective). The bonds get the isotropic cubic influence function and
        the surface correction by default; the other keywords as in :class:`IceBody`. At rest,
        regions still to add."""
        part = lattice_part(shape, dx, delta, comm, isotropic=isotropic,
                            surface_correction=surface_correction)
        return cls(name, material=material, dx=dx, delta=delta, loop=loop, failure=failure,
                   keep_bond_length=keep_bond_length, **part)

    # -- arrays and counts ---------------------------------------------------------------------
    row_ptr = property(lambda self: self.bonds.row_ptr)
    nbr = property(lambda self: self.bonds.nbr)
    xi_len = property(lambda self: self.bonds.xi_len)
    weight = property(lambda self: self.bonds.weight)

    @property
    def n(self) -> int:
        """Number of local particles (all of them for a whole body)."""
        return self.x0.shape[0]

    @property
    def n_global(self) -> int:
        """Number of particles of the whole body."""
        return self.layout.n_global

    @property
    def owned(self) -> np.ndarray:
        """(n,) bool: the local particles this process owns."""
        return self.layout.owned

    @property
    def gid(self) -> np.ndarray:
        """(n,) global numbers of the local particles."""
        return self.layout.gid

    @property
    def layout_version(self) -> int:
        """Incremented when particles move between ranks (local numbers change)."""
        return self.layout.version

    def counted_bonds(self) -> np.ndarray:
        """(P,) bool: the local bonds this process counts (its owned particles' rows): each
        bond of the body is counted on one process."""
        return np.repeat(self.layout.owned, np.diff(self.bonds.row_ptr))

    def counts(self) -> tuple[int, int, int]:
        """Particles, bonds and broken bonds of the whole body (collective)."""
        broken = self.bonds.broken_flags()[self.counted_bonds()].sum(dtype=np.int64)
        return self.n_global, self.n_bonds, int(self.layout.allsum(broken))

    def broken_arg(self) -> np.ndarray:
        """What the kernels take as ``broken``: :data:`~pdfem.pd.bonds.pair_loop.SIGNED`."""
        return SIGNED

    @property
    def broken(self) -> np.ndarray:
        """(P,) uint8 broken flags, 1 = broken (a copy: assign to change them)."""
        return self.bonds.broken_flags()

    @broken.setter
    def broken(self, flags: np.ndarray) -> None:
        self.ledger.forget()  # set from outside the time loop: no dissipation
        self.workspace.lengths_current = False
        self.bonds.weight[:] = kernels.signed_weights(self.bonds.weight, flags)
        self.intact.forget()
        self.update_intact_volume()

    @property
    def m_now(self) -> np.ndarray:
        """(n,) weighted volume of the intact bonds (m^5)."""
        return self.intact.now

    def update_intact_volume(self) -> None:
        """Bring :attr:`m_now` up to date with the broken bonds, the halo's from their owners."""
        b = self.bonds
        self.intact.update(b.row_ptr, b.nbr, b.xi_len, b.weight, self.broken != 0, self.vol)
        self.layout.exchange(self.intact.now)

    @property
    def s0(self) -> float:
        """The stretch above which bonds break at zero dilatation (inf: never)."""
        return self.failure.stretch_limits()[0]

    @property
    def limits(self) -> tuple[float, ...]:
        """The failure law's stretch bounds (t0, t1, c0, c1, d0, d1) the kernels take."""
        return self.failure.stretch_limits()

    @property
    def strength_factors(self) -> np.ndarray | None:
        """(n,) factors on the compressive strength from the strain rates (None: 1)."""
        return None if self.rates is None else self.rates.factors

    # -- set-up --------------------------------------------------------------------------------
    def cut_crack(self, point, normal, lo, hi) -> int:
        """Break the bonds crossing a planar pre-crack (:func:`pdfem.pd.bonds.geometry.
        cut_crack`); returns the bonds this process counts as cut."""
        nrm = np.asarray(normal, dtype=np.float64)
        nrm = nrm / np.linalg.norm(nrm)
        flags = self.broken
        before = flags[self.counted_bonds()].sum(dtype=np.int64)
        cut_crack(self.x0, self.row_ptr, self.nbr, flags, np.asarray(point, np.float64), nrm,
                  np.asarray(lo, np.float64), np.asarray(hi, np.float64))
        self.broken = flags
        return int(flags[self.counted_bonds()].sum(dtype=np.int64) - before)

    def add_velocity_constraint(self, mask: np.ndarray, velocity=(0.0, 0.0, 0.0),
                                ramp_time: float = 0.0, *, path=None, name: str = "") -> None:
        """Prescribe the motion of the owned particles in ``mask``: ``velocity`` (m/s, ramped
        over ``ramp_time`` s) or a displacement ``path`` (:mod:`pdfem.pd.constraints`, which
        they are put on now); ``name`` (default ``prescribed<k>``) names its reaction."""
        idx = np.flatnonzero(mask & self.layout.owned).astype(np.int64)
        c = VelocityConstraint(idx, np.asarray(velocity, dtype=np.float64), float(ramp_time), path,
                               name or next_name(self.constraints, "prescribed"))
        self.constraints.append(c)
        c.impose(self, self.time)
        self.workspace.lengths_current = False

    def fix(self, mask: np.ndarray, name: str = "") -> None:
        """Hold the particles in ``mask`` in place; ``name`` (default ``fixed<k>``) names the
        region's reaction."""
        self.add_velocity_constraint(mask, name=name or next_name(self.constraints, "fixed"))
        self.fixed |= mask
        self._fixed_rows = (self.fixed, np.flatnonzero(self.fixed))

    def stable_time_step(self) -> float:
        """A stable velocity-Verlet step (s) of the whole body, safe for every body shape
        (:func:`pdfem.pd.timestep.body_stable_time_step`; collective)."""
        return body_stable_time_step(self)

    # -- physics -------------------------------------------------------------------------------
    def compute_forces(self) -> int:
        """Positions exchanged, dilatation (exchanged), then force density and bond breaking at
        the current positions; the strain energy the broken bonds held goes to
        :attr:`fracture_dissipated` (:mod:`pdfem.pd.failure.fracture`). Returns the number of
        bonds of the whole body that broke (collective)."""
        self.ledger.prepare(self)
        lay, mat, b = self.layout, self.material, self.bonds
        lay.exchange(self.y)
        if self.family is None:
            broke = kernels.dilatation_and_forces(
                self.y, b.row_ptr, b.nbr, b.xi_len, b.weight, SIGNED, self.vol, self.m, mat.K,
                mat.mu, self.limits, self.nofail, self.theta, self.f, self.workspace,
                between=lay.exchange, rest=self.rest, crush_yield=self.failure.crush_yield,
                owned=lay.counted_rows, strength=self.strength_factors, m_now=self.m_now,
                shear=self.shear)
        else:
            fam_ptr, fam_nbr, fam_bond = self.family
            kernels.dilatation_family(self.y, fam_ptr, fam_nbr, fam_bond, b.xi_len, b.weight,
                                      SIGNED, self.vol, self.m, self.theta)
            lay.exchange(self.theta)
            broke = kernels.forces_family(self.y, fam_ptr, fam_nbr, fam_bond, b.xi_len,
                                          b.weight, SIGNED, self.vol, self.m, self.theta, mat.K,
                                          mat.mu, self.limits, self.nofail, self.f,
                                          m_now=self.m_now)
        new = 0
        if broke:
            released, new = self.ledger.released(self, lay.owned)
            self.local_fracture_dissipated += released
        if self.rest is not None:
            self.local_fracture_dissipated += self.workspace.crush_dissipated
        total = int(lay.allsum(new))
        if total:
            self.update_intact_volume()
        return total

    def refresh_forces(self) -> None:
        """The forces without the bonds the last pass broke, recomputed until no further bond
        breaks (a failure law whose bounds depend on the dilatation can break more once some
        are gone; collective)."""
        while self.compute_forces():
            pass

    def apply_constraints(self, t: float, step: float = 0.0) -> None:
        """The prescribed motion at ``t`` (s); with ``step``, the drift velocity over it."""
        mask, rows = self._fixed_rows
        if mask is not self.fixed:  # a new fixed set (taken from elsewhere)
            self._fixed_rows = mask, rows = self.fixed, np.flatnonzero(self.fixed)
        set_rows(self.v, rows, _REST)
        for c in self.constraints:
            c.impose(self, t, step)
            if c.path is not None and not step:  # positions put on the path, past the pass
                self.workspace.lengths_current = False

    def start(self) -> None:
        """Compute the forces of the initial state (call once before the first step); bonds
        breaking here are no dissipation of the run (the run starts from the state after)."""
        self.apply_constraints(self.time)
        before = self.local_fracture_dissipated
        self.refresh_forces()
        self.local_fracture_dissipated = before

    def begin_step(self, dt: float, keep_old: bool = False,
                   drift: bool = True) -> np.ndarray | None:
        """First half of a velocity-Verlet step: half kick, constraints, position update.
        Returns the positions before the update if ``keep_old`` (contact needs them), else
        ``None``. With ``drift=False`` the positions are left as they are, for the caller to
        move (the coupler drifts them in the structures' substeps). Follow with
        :meth:`compute_forces` (plus any extra force density added to ``f``) and
        :meth:`end_step`."""
        half = 0.5 * dt
        t0 = self.time
        if self.rates is not None:
            self.rates.advance(self.theta, dt)
        # the forces on the prescribed regions at the step's start, for the work of those
        # that move (a held region does none)
        moving = any(c.moves for c in self.constraints)
        self._force0 = applied_forces(self) if moving else None
        verlet_kick(self.v, self.f, 1.0 / self.material.density, half, self.gravity)
        self.apply_constraints(t0, dt)
        y_old = self.y.copy() if keep_old else None
        if self.shear is not None:  # the springs advance by this step's change of the bonds
            self.shear.begin_step(self.y)
        if drift:
            self.y += dt * self.v
        self.time = t0 + dt
        return y_old

    def end_step(self, dt: float) -> None:
        """Second half of the step begun by :meth:`begin_step`, once ``f`` holds the forces at
        the new positions: half kick, constraints, work of the constraints."""
        half = 0.5 * dt
        verlet_kick(self.v, self.f, 1.0 / self.material.density, half, self.gravity)
        self.apply_constraints(self.time)
        if self._force0 is not None:
            self.local_external_work += step_work(self, self._force0, dt)

    def step(self, dt: float, after_drift=None) -> int:
        """Advance by ``dt`` (s) with velocity Verlet; the number of bonds broken. ``after_drift
        (y_old)``, if given, may correct ``y`` and ``v`` right after the position update."""
        y_old = self.begin_step(dt, keep_old=after_drift is not None)
        if after_drift is not None:
            after_drift(y_old)
        nbroken = self.compute_forces()
        self.end_step(dt)
        if nbroken:
            self.refresh_forces()  # the broken bonds acted in this step, not in the next
        return nbroken

    # -- totals over the whole body (collective) -----------------------------------------------
    @property
    def external_work(self) -> float:
        """Work (J) of the prescribed motions on the whole body so far."""
        return float(self.layout.allsum(self.local_external_work))

    @external_work.setter
    def external_work(self, value: float) -> None:
        self.local_external_work = value if self.layout.comm.rank == 0 else 0.0

    @property
    def fracture_dissipated(self) -> float:
        """Energy (J) released by the bonds broken since the start, the whole body."""
        return float(self.layout.allsum(self.local_fracture_dissipated))

    def owned_sum(self, values: np.ndarray):
        """A per-particle array summed over the owned particles of every process, correctly
        rounded (the same on 1 and N ranks)."""
        return self.layout.owned_sum(values)

    def reactions(self) -> dict[str, np.ndarray]:
        """The reaction (N, global axes) of each fixed or prescribed region by name: the force
        its support or driver exerts on the ice now (:mod:`pdfem.pd.constraints`)."""
        return dict(zip([c.name for c in self.constraints], reaction_forces(self)))

    def displacement(self) -> np.ndarray:
        """(n, 3) displacement y - x0, m."""
        return self.y - self.x0

    def damage(self) -> np.ndarray:
        """(n,) broken fraction of each particle's initial bonds (right for owned ones)."""
        return diagnostics.damage(self)

    def kinetic_energy(self) -> float:
        """Kinetic energy of the whole body, J."""
        return diagnostics.kinetic_energy(self)

    def kinetic_correction(self, step: float) -> float:
        """Velocity Verlet's share of the kinetic energy at the ice step ``step`` (s), the
        whole body, J (:func:`pdfem.pd.diagnostics.kinetic_correction`)."""
        return diagnostics.kinetic_correction(self, step)

    def strain_energy(self, forces_current: bool = False) -> float:
        """Elastic energy of the unbroken bonds (and of the crushed bonds that still push) at
        the current positions, the whole body, J; ``forces_current``: the forces were last
        computed at these positions with these bonds (after a time step; skips a pass,
        :func:`pdfem.pd.diagnostics.strain_energy`)."""
        return diagnostics.strain_energy(self, forces_current)

    def momentum(self) -> np.ndarray:
        """Linear momentum (3,) of the whole body, kg m/s."""
        return diagnostics.momentum(self)

    # -- output --------------------------------------------------------------------------------
    def gather(self, values: np.ndarray) -> np.ndarray | None:
        """The owned rows of a local per-particle array in global order on rank 0 (None on the
        others; collective)."""
        return self.layout.gather(values)

    def frame_fields(self) -> dict[str, np.ndarray] | None:
        """``{"u" m, "v" m/s, "damage"}`` in global order on rank 0 (None elsewhere;
        collective)."""
        u = self.gather(self.displacement())
        v = self.gather(self.v)
        d = self.gather(self.damage())
        return None if u is None else {"u": u, "v": v, "damage": d}

    def owned_reference(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Global numbers, reference positions (m) and volumes (m^3) of the owned particles."""
        own = self.layout.owned
        return self.layout.gid[own], self.x0[own], self.vol[own]

    def owned_frame_fields(self) -> dict[str, np.ndarray]:
        """``{"u", "v", "damage"}`` of the owned particles, in :meth:`owned_reference` order."""
        own = self.layout.owned
        return {"u": self.displacement()[own], "v": self.v[own], "damage": self.damage()[own]}

    # -- load balance and checkpoints ----------------------------------------------------------
    def imbalance(self) -> float:
        """Largest process's bond work over the mean (1: balanced; collective)."""
        return balance.imbalance(self)

    def rebalance(self, carry: dict[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
        """Re-partition over the ranks and move the particles and bonds
        (:mod:`pdfem.pd.layout.rebalance`); ``carry`` holds other per-particle arrays that move
        with the particles, returned in the new local order (collective)."""
        moved = balance.rebalance(self, carry)
        if moved is None:
            return dict(carry or {})
        other, carried = moved
        vars(self).update(vars(other))  # this object is the body that moved
        return carried

    def checkpoint_state(self) -> dict:
        """The state a restart needs (:func:`pdfem.pd.checkpoint.state.checkpoint_state`)."""
        return checkpoint.checkpoint_state(self)

    def restore_state(self, state: dict) -> None:
        """Put a state from :meth:`checkpoint_state` back, bit for bit (collective)."""
        checkpoint.restore_state(self, state)

    def checkpoint_layout(self):
        """Which particles and bonds this process holds (:class:`pdfem.pd.checkpoint.parts.
        Layout`)."""
        return checkpoint.part_layout(self)
