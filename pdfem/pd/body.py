"""An ice body: particles, bonds and state arrays, advanced by velocity-Verlet steps.

The class holds flat arrays and calls the numba kernels of :mod:`pdfem.pd.bonds.kernels` (no loops of
its own). Particles are numbered in cell order, so bond partners sit close in memory.

Bodies filled with a cubic lattice (:meth:`IceBody.from_shape`, hence every body of a case file)
weigh their bonds with the cubic influence function of :mod:`pdfem.pd.bonds.influence`, which makes the
lattice LPS isotropic (E and nu as input, not E = 0.89 E_input and nu = 0.32 along the lattice
axes), and correct the weights near free surfaces (:mod:`pdfem.pd.bonds.surface`), which removes the
stiff surface layers of the LPS; bodies from arbitrary point clouds
(:meth:`IceBody.from_points`) use w = 1 and no correction unless asked.

Bonds cost 16 bytes each: int32 partner (``nbr``), float64 reference length (``xi_len``) and a
float32 weight (``weight``) whose sign marks a broken bond (:data:`pdfem.pd.bonds.kernels.SIGNED`);
``broken`` gives the flags as a uint8 copy. Which bonds break is the body's failure law's
decision (:mod:`pdfem.pd.failure`; default: the material's critical stretch), which gives the
kernels their threshold. The body implements the ice-body interface that contact, particle
forces and output use (:class:`pdfem.pd.ice_interface.IceParticles`), as a whole body: every
particle is owned. The strain energy that breaking bonds take with them is counted in
``fracture_dissipated`` (:mod:`pdfem.pd.failure.fracture`).

One step (:meth:`IceBody.step`), with force density f (N/m^3) and density rho (kg/m^3)::

    v += dt/2 (f/rho + g)        kick
    v = prescribed on constrained particles
    y += dt v                    drift
    theta(y); f(y, theta)        dilatation, then forces and bond breaking
    v += dt/2 (f/rho + g)        kick
    v = prescribed on constrained particles

with g the uniform body acceleration ``gravity`` (set by :class:`pdfem.forces.gravity.Gravity`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pdfem.pd.bonds import kernels
from pdfem.pd.body_diagnostics import BodyDiagnostics
from pdfem.pd.checkpoint.state import BodyCheckpoint
from pdfem.pd.bonds.geometry import bond_lengths, cut_crack
from pdfem.pd.failure.damaged_volume import IntactVolume
from pdfem.pd.constraints import VelocityConstraint, applied_forces, next_name, step_work
from pdfem.pd.constraints import reaction_forces
from pdfem.pd.failure.crushed_shear import CrushedShear
from pdfem.pd.failure import CriticalStretch, FailureLaw
from pdfem.pd.failure.fracture import FractureLedger
from pdfem.pd.ice_interface import WholeBody
from pdfem.pd.bonds.family import build_family
from pdfem.pd.bonds.influence import bond_weights, isotropy_gain
from pdfem.pd.bonds.surface import surface_corrected_weights
from pdfem.geometry.lattice import fill
from pdfem.pd.materials.lps import IceMaterial
from pdfem.pd.bonds.pair_loop import SIGNED
from pdfem.pd.bonds.search import cell_pairs
from pdfem.pd.failure.strain_rate import RateTracker


@dataclass
class IceBody(BodyCheckpoint, BodyDiagnostics, WholeBody):
    """State of one peridynamic ice body (all arrays SI, particles in cell order); build one
    with :meth:`from_points` (or :func:`pdfem.run.build_ice.build_ice_body` from a case)."""

    name: str
    x0: np.ndarray            # (N,3) reference positions, m
    vol: np.ndarray           # (N,) particle volumes, m^3
    material: IceMaterial
    dx: float                 # lattice spacing, m
    delta: float              # horizon, m
    row_ptr: np.ndarray       # (N+1,) int64
    nbr: np.ndarray           # (P,) int32, unique pairs i < nbr
    xi_len: np.ndarray        # (P,) reference bond lengths, m
    nofail: np.ndarray        # (N,) uint8
    y: np.ndarray = None      # (N,3) positions, m
    v: np.ndarray = None      # (N,3) velocities, m/s
    f: np.ndarray = None      # (N,3) force density, N/m^3
    m: np.ndarray = None      # (N,) weighted volume, m^5
    theta: np.ndarray = None  # (N,) dilatation
    weight: np.ndarray = None  # (P,) float32 bond weights omega = w beta, negative = broken
    influence_gain: float = 0.0  # gain g of the cubic influence function (0: w = 1)
    loop: str = "pairs"
    # uniform body acceleration (m/s^2) of the kick, set by pdfem.forces.gravity.Gravity
    gravity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    fixed: np.ndarray = None  # (N,) bool
    constraints: list = field(default_factory=list)
    external_work: float = 0.0
    # energy (J) released by the bonds broken in the steps so far (pdfem.pd.failure.fracture)
    fracture_dissipated: float = 0.0
    time: float = 0.0
    failure: FailureLaw | None = None  # default: critical stretch of the material at delta
    # Optional (P,) uint8 broken flags (else a broken bond is a negative weight, as builders
    # make bodies); given, the kernels update them in place and ``broken`` is them.
    flags: np.ndarray | None = field(default=None, repr=False, compare=False)
    # (P,) float32 stretch at which each bond broke, NaN if intact or broken for good: with a
    # failure law whose broken bonds keep pushing in compression (crushed ice), else None
    rest: np.ndarray | None = field(default=None, repr=False, compare=False)
    # crushed bonds' shear springs (pdfem.pd.failure.crushed_shear) if crushed ice has friction
    shear: CrushedShear | None = field(default=None, repr=False, compare=False)
    # strain rates and strength factors, for a law whose strength depends on the rate
    rates: RateTracker | None = field(default=None, repr=False, compare=False)
    # (N,) global particle numbers of a rank's part of a body (summation order); None: own
    gid: np.ndarray | None = field(default=None, repr=False, compare=False)
    # the weighted volume of the intact bonds (pdfem.pd.failure.damaged_volume)
    _intact: IntactVolume | None = field(default=None, init=False, repr=False, compare=False)
    _ledger: FractureLedger = field(default_factory=FractureLedger, init=False, repr=False,
                                    compare=False)

    def __post_init__(self) -> None:
        if self.failure is None:
            self.failure = CriticalStretch.from_material(self.material, self.delta)
        if self.failure.broken_bonds_push and self.rest is None:
            if self.loop != "pairs":
                raise ValueError(f"the {self.failure.name!r} failure law needs the pair loop "
                                 "(pd_loop = \"pairs\")")
            self.rest = np.full(self.nbr.shape[0], np.nan, dtype=np.float32)
        if self.failure.crush_friction > 0.0 and self.shear is None:
            self.shear = CrushedShear.for_bonds(self.nbr.shape[0], self.failure.crush_friction)
        if self.failure.rate_dependent and self.rates is None:
            self.rates = RateTracker(self.failure, self.material.poisson_ratio)

    @classmethod
    def from_points(cls, name: str, x: np.ndarray, material: IceMaterial, dx: float, delta: float,
                    *, loop: str = "pairs", volume: np.ndarray | None = None,
                    isotropic: bool = False, surface_correction: bool = False,
                    failure: FailureLaw | None = None) -> "IceBody":
        """Build a body from particle positions: cell-sort them, find bonds, set up state.

        Parameters
        ----------
        name
            Body name (used in results).
        x
            (N,3) particle positions, m; renumbered into cell order.
        material
            Ice material.
        dx
            Lattice spacing, m (particle volume dx^3 unless ``volume`` is given).
        delta
            Horizon, m.
        loop
            ``"pairs"`` (the particle-pair loop) or ``"full_family"`` (per-particle reference).
        volume
            Optional (N,) particle volumes, m^3, in the order of ``x``.
        isotropic
            Weigh the bonds with the cubic influence function that makes a cubic lattice of
            spacing ``dx`` aligned with the axes isotropic
            (:func:`pdfem.pd.bonds.influence.isotropy_gain`); only right for such lattices.
            False: w = 1.
        surface_correction
            Correct the bond weights so that every family's second moment is isotropic
            (:func:`pdfem.pd.bonds.surface.surface_corrected_weights`).
        failure
            The failure law of the bonds (:mod:`pdfem.pd.failure`); default: the critical
            stretch of ``material`` at ``delta``.

        Raises
        ------
        ValueError
            For an unknown ``loop``, or ``isotropic`` with a horizon too small for it.
        """
        if loop not in ("pairs", "full_family"):
            raise ValueError(f"unknown PD loop {loop!r}; valid: 'pairs', 'full_family'")
        gain = isotropy_gain(delta / dx) if isotropic else 0.0
        x = np.ascontiguousarray(x, dtype=np.float64)
        perm, row_ptr, nbr = cell_pairs(x, delta)
        x0 = np.ascontiguousarray(x[perm])
        n = x0.shape[0]
        vol = (np.full(n, dx ** 3) if volume is None
               else np.ascontiguousarray(np.asarray(volume, dtype=np.float64)[perm]))
        body = cls(name=name, x0=x0, vol=vol, material=material, dx=float(dx), delta=float(delta),
                   row_ptr=row_ptr, nbr=nbr, xi_len=bond_lengths(x0, row_ptr, nbr),
                   nofail=np.zeros(n, dtype=np.uint8), loop=loop, failure=failure)
        body.y = x0.copy()
        body.v = np.zeros_like(x0)
        body.f = np.zeros_like(x0)
        body.theta = np.zeros(n)
        body.fixed = np.zeros(n, dtype=bool)
        body.influence_gain = gain
        body.weight = bond_weights(x0, row_ptr, nbr, body.xi_len, body.delta, body.dx, gain)
        body._ws = kernels.PairWorkspace(row_ptr, nbr)
        if surface_correction:
            surface_corrected_weights(x0, row_ptr, nbr, body.xi_len, body.weight, vol, ws=body._ws,
                                      out=body.weight)
        body.m = kernels.weighted_volume(row_ptr, nbr, body.xi_len, body.weight, vol, body._ws)
        if loop == "full_family":
            body._family = build_family(row_ptr, nbr, n)
        return body

    @classmethod
    def from_shape(cls, name: str, shape, material: IceMaterial, dx: float, delta: float,
                   **kwargs) -> "IceBody":
        """Fill ``shape`` (a :mod:`pdfem.geometry.shapes` object) with a cubic lattice of spacing ``dx``.

        The lattice is aligned with the axes, so the bonds get the isotropic cubic influence
        function and the surface correction by default (``isotropic=True``,
        ``surface_correction=True``); other keywords as in :meth:`from_points`.
        """
        kwargs.setdefault("isotropic", True)
        kwargs.setdefault("surface_correction", True)
        return cls.from_points(name, fill(shape, dx), material, dx, delta, **kwargs)

    # -- set-up ------------------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of particles."""
        return self.x0.shape[0]

    @property
    def n_bonds(self) -> int:
        """Number of unique bonds (pairs)."""
        return self.nbr.shape[0]

    def _broken_arg(self) -> np.ndarray:
        """What the kernels get as ``broken``: the flag array, or SIGNED (negative weights)."""
        return SIGNED if self.flags is None else self.flags

    @property
    def broken(self) -> np.ndarray:
        """(P,) uint8 broken flags, 1 = broken. For a body that stores broken bonds as negative
        weights (16 bytes per pair) this is a copy; assign a flag array to change the flags."""
        return kernels.broken_flags(self.weight) if self.flags is None else self.flags

    @broken.setter
    def broken(self, flags: np.ndarray) -> None:
        self._ledger.forget()  # set from outside the time loop: no dissipation
        if self.flags is None:
            self.weight[:] = kernels.signed_weights(self.weight, flags)
        else:
            self.flags[:] = flags
        if self._intact is not None:
            self._intact.forget()
        self.update_intact_volume()

    @property
    def m_now(self) -> np.ndarray | None:
        """(N,) weighted volume of the intact bonds (m^5); None before any bond broke."""
        return None if self._intact is None else self._intact.now

    def update_intact_volume(self) -> None:
        """Bring :attr:`m_now` up to date with the broken bonds (after bonds broke)."""
        if self._intact is None:
            self._intact = IntactVolume(self.m, self.gid)
        self._intact.update(self.row_ptr, self.nbr, self.xi_len, self.weight, self.broken != 0,
                            self.vol)

    @property
    def s0(self) -> float:
        """The stretch above which bonds break at zero dilatation (:attr:`failure`; inf: never)."""
        return self.failure.stretch_limits()[0]

    @property
    def strength_factors(self) -> np.ndarray | None:
        """(N,) factors on the compressive strength from the strain rates (None: 1)."""
        return None if self.rates is None else self.rates.factors

    @property
    def limits(self) -> tuple[float, ...]:
        """The failure law's stretch bounds (t0, t1, c0, c1, d0, d1) the kernels take
        (:meth:`pdfem.pd.failure.base.FailureLaw.stretch_limits`)."""
        return self.failure.stretch_limits()

    def cut_crack(self, point, normal, lo, hi) -> int:
        """Break the bonds crossing a planar pre-crack (see :func:`pdfem.pd.bonds.geometry.cut_crack`)."""
        nrm = np.asarray(normal, dtype=np.float64)
        nrm = nrm / np.linalg.norm(nrm)
        flags = self.broken
        count = cut_crack(self.x0, self.row_ptr, self.nbr, flags, np.asarray(point, np.float64),
                          nrm, np.asarray(lo, np.float64), np.asarray(hi, np.float64))
        self.broken = flags
        return count

    def add_velocity_constraint(self, mask: np.ndarray, velocity=(0.0, 0.0, 0.0),
                                ramp_time: float = 0.0, *, path=None, name: str = "") -> None:
        """Prescribe the motion of the particles in ``mask``: ``velocity`` (m/s, ramped over
        ``ramp_time`` s) or a displacement ``path`` (:mod:`pdfem.pd.constraints`, which they are
        put on now); ``name`` (default ``prescribed<k>``) names its reaction."""
        idx = np.flatnonzero(mask).astype(np.int64)
        c = VelocityConstraint(idx, np.asarray(velocity, dtype=np.float64), float(ramp_time), path,
                               name or next_name(self.constraints, "prescribed"))
        self.constraints.append(c)
        c.impose(self, self.time)

    def fix(self, mask: np.ndarray, name: str = "") -> None:
        """Hold the particles in ``mask`` in place; ``name`` (default ``fixed<k>``) names the
        region's reaction."""
        self.add_velocity_constraint(mask, name=name or next_name(self.constraints, "fixed"))
        self.fixed |= mask

    # -- physics -------------------------------------------------------------------------------
    def compute_forces(self) -> int:
        """Dilatation, then force density and bond breaking at the current positions; the
        strain energy the broken bonds held goes to :attr:`fracture_dissipated`
        (:mod:`pdfem.pd.failure.fracture`). Returns the number of bonds that broke."""
        self._ledger.prepare(self)
        mat = self.material
        br = self._broken_arg()
        if self.loop == "pairs":
            nb = kernels.dilatation_and_forces(self.y, self.row_ptr, self.nbr, self.xi_len,
                                               self.weight, br, self.vol, self.m, mat.K, mat.mu,
                                               self.limits, self.nofail, self.theta, self.f,
                                               self._ws, rest=self.rest,
                                               crush_yield=self.failure.crush_yield,
                                               strength=self.strength_factors, m_now=self.m_now,
                                               shear=self.shear)
        else:
            fam_ptr, fam_nbr, fam_bond = self._family
            kernels.dilatation_family(self.y, fam_ptr, fam_nbr, fam_bond, self.xi_len,
                                      self.weight, br, self.vol, self.m, self.theta)
            nb = kernels.forces_family(self.y, fam_ptr, fam_nbr, fam_bond, self.xi_len,
                                       self.weight, br, self.vol, self.m, self.theta, mat.K,
                                       mat.mu, self.limits, self.nofail, self.f,
                                       m_now=self.m_now)
        if nb:
            self.fracture_dissipated += self._ledger.released(self)
            self.update_intact_volume()
        if self.rest is not None:
            self.fracture_dissipated += self._ws.crush_dissipated
        return nb

    def _apply_constraints(self, t: float, step: float = 0.0) -> None:
        """The prescribed motion at ``t`` (s); with ``step``, the drift velocity over it."""
        self.v[self.fixed] = 0.0
        for c in self.constraints:
            c.impose(self, t, step)

    def reactions(self) -> dict[str, np.ndarray]:
        """The reaction (N, global axes) of each fixed or prescribed region by name: the force
        its support or driver exerts on the ice now (:mod:`pdfem.pd.constraints`)."""
        return dict(zip([c.name for c in self.constraints], reaction_forces(self)))

    def stable_time_step(self) -> float:
        """A stable velocity-Verlet step (s) for this body, safe for every body shape.

        The smaller of Silling & Askari's estimate and the Gershgorin bound of the linearised
        LPS (:func:`pdfem.pd.timestep.stable_time_step` without and with ``mu``), both with the
        bond weights. The Gershgorin bound is guaranteed below the true critical step for any
        shape; Silling & Askari's estimate is not for bodies one or two particles thick, and it
        only wins (is smaller) on bodies where it is safe. No further safety factor is applied.
        """
        mat = self.material
        args = (self.row_ptr, self.nbr, self.xi_len, self.weight, self.vol, self.delta,
                mat.density, mat.K)
        return min(kernels.stable_time_step(*args, ws=self._ws),
                   kernels.stable_time_step(*args, mat.mu, self._ws))

    def start(self) -> None:
        """Compute the forces of the initial state (call once before the first step); bonds
        breaking here are no dissipation of the run (the run starts from the state after)."""
        self._apply_constraints(self.time)
        before = self.fracture_dissipated
        self.refresh_forces()
        self.fracture_dissipated = before

    def begin_step(self, dt: float, keep_old: bool = False) -> np.ndarray | None:
        """First half of a velocity-Verlet step: half kick, constraints, position update.
        Returns the positions before the update if ``keep_old`` (contact needs them), else
        ``None``. Follow with :meth:`compute_forces` (plus any extra force density added to
        ``f``) and :meth:`end_step`."""
        half = 0.5 * dt
        t0 = self.time
        if self.rates is not None:
            self.rates.advance(self.theta, dt)
        self._force0 = applied_forces(self) if self.constraints else None
        self.v += half * (self.f * (1.0 / self.material.density) + self.gravity)
        self._apply_constraints(t0, dt)
        y_old = self.y.copy() if keep_old else None
        if self.shear is not None:  # the springs advance by this step's change of the bonds
            self.shear.begin_step(self.y)
        self.y += dt * self.v
        self.time = t0 + dt
        return y_old

    def end_step(self, dt: float) -> None:
        """Second half of the step begun by :meth:`begin_step`, once ``f`` holds the forces at
        the new positions: half kick, constraints, work of the constraints."""
        half = 0.5 * dt
        self.v += half * (self.f * (1.0 / self.material.density) + self.gravity)
        self._apply_constraints(self.time)
        if self.constraints:
            self.external_work += step_work(self, self._force0, dt)

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

    def refresh_forces(self) -> None:
        """The forces without the bonds the last pass broke, recomputed until no further bond
        breaks (:meth:`pdfem.pd.ice_interface.IceParticles.refresh_forces`)."""
        while self.compute_forces():
            pass
