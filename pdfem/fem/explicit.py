"""Explicit central-difference time integration of ``M a + C v + K u = f`` with lumped mass.

The scheme is the central difference method in its velocity form (kick-drift-kick, equivalent
to leapfrog; Belytschko, Liu & Moran, *Nonlinear Finite Elements*, Sec. 6.2), with step dt
(s)::

    v_half = v + dt/2 a
    u     += dt v_half                     then prescribed displacements on Dirichlet DOFs
    a      = (f_ext - K u - C v_half) / m  (zero on Dirichlet DOFs)
    v      = v_half + dt/2 a

``m`` is the lumped (diagonal) mass, ``C = alpha M + beta K`` optional Rayleigh damping taken with
the mid-step velocity (the usual explicit treatment). Without damping the scheme conserves the
discrete energy ``1/2 v_half(n-1/2) . M v_half(n+1/2) + 1/2 u . K u`` exactly.

Energy. Over a step the kinetic energy changes by exactly the trapezoidal work
``1/2 (F_n + F_n+1) . (u_n+1 - u_n)`` of the total force ``F = M a`` plus a bounded term
that telescopes, ``-(dt^2/8) a . M a`` (:meth:`CentralDifference.kinetic_correction`); the
internal force's share is minus the change of ``1/2 u . K u``. So the integrator keeps, per
step and with the same rule, the work of the external forces (``work_external``), of the
supports that move (``work_supports``, reaction times prescribed motion) and the energy the
damping takes (``damping_dissipated``), and the balance
``kinetic + correction + strain = initial + work_external + work_supports - damping_dissipated
+ work of impulses`` holds to round-off (impulses: :meth:`CentralDifference.apply_impulse`,
whose work is ``v . J + J^2 / (2 m)`` at that instant).

The stable step is ``dt_c = 2 / omega_max`` (reduced to ``(2/omega) (sqrt(1 + xi^2) - xi)`` with
the damping ratio ``xi`` of the highest mode when damping is on), ``omega_max^2`` the largest
eigenvalue of ``M^-1 K`` restricted to the free DOFs. It is found by power iteration on the
symmetric ``M^-1/2 K M^-1/2`` with the Rayleigh quotient, which approaches ``omega_max^2`` from
below, and cached; :meth:`CentralDifference.stable_time_step` multiplies ``dt_c`` by a safety
factor (default 0.9).

Arrays are DOF vectors in scikit-fem's order (:class:`pdfem.fem.elasticity.DofMap`); SI units:
displacement m, velocity m/s, force N, mass kg, time s.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
import scipy.sparse as sp

from pdfem.fem.central_difference_kernels import NO_OFFSET, correct, predict, trapezoid_work
from pdfem.fem.node_blocks import NodeBlockOperator, NodeBlockPair

Prescribed = Callable[[float], np.ndarray]


class StepStart(NamedTuple):
    """The first half of a central-difference step (:meth:`CentralDifference.begin_step`)."""

    dt: float                  # s, the step
    v_half: np.ndarray         # m/s, mid-step velocity
    u: np.ndarray              # m, displacement at the step's end
    f_damp: np.ndarray         # N, damping force of the mid-step velocity
    ku: np.ndarray             # N, K u at the step's end
    cu: np.ndarray | None      # N, the companion matrix's product (None without one)
    moving: bool               # whether prescribed supports move (their reaction works)


def power_iteration_max_eigenvalue(stiffness: sp.spmatrix, mass: np.ndarray,
                                   free: np.ndarray | None = None, max_iterations: int = 200,
                                   min_iterations: int = 50, rtol: float = 1e-6,
                                   seed: int = 0) -> tuple[float, int]:
    """Largest eigenvalue of ``M^-1 K`` on the free DOFs by power iteration.

    Iterates ``x <- A x / |A x|`` with ``A = M^-1/2 K_ff M^-1/2`` from a fixed pseudo-random start
    and returns the Rayleigh quotient ``x . A x``, which is a lower bound that increases towards
    the largest eigenvalue. Stops after ``max_iterations``, or once ``min_iterations`` are done
    and the relative change of the quotient over the last 10 iterations is below ``rtol``.

    Parameters
    ----------
    stiffness
        Symmetric stiffness matrix K (N/m), (n, n).
    mass
        Lumped mass (kg), (n,), all > 0.
    free
        Boolean mask (n,) of unconstrained DOFs (default: all).
    max_iterations, min_iterations
        Iteration limits.
    rtol
        Relative convergence tolerance of the Rayleigh quotient.
    seed
        Seed of the start vector (the result is deterministic for a given seed).

    Returns
    -------
    lam, iterations
        The estimate of ``omega_max^2`` (1/s^2) and the number of iterations done.
    """
    n = stiffness.shape[0]
    d = 1.0 / np.sqrt(np.asarray(mass, dtype=np.float64))
    if free is not None:
        d = np.where(free, d, 0.0)
    if not np.any(d > 0.0):
        return 0.0, 0
    x = np.random.default_rng(seed).standard_normal(n) * (d > 0.0)
    x /= np.linalg.norm(x)
    history: list[float] = []
    lam = 0.0
    it = 0
    for it in range(1, max_iterations + 1):
        with np.errstate(over="ignore", invalid="ignore"):  # a non-finite y returns inf below
            y = d * (stiffness @ (d * x))
            lam = float(x @ y)
        history.append(lam)
        big = float(np.abs(y).max())
        if big == 0.0:
            return 0.0, it
        if not math.isfinite(big):  # K overflowed: no finite step is stable
            return math.inf, it
        if not 1e-150 < big < 1e150:  # |y|^2 would overflow or underflow: scale first
            y = y / big
        x = y / np.linalg.norm(y)
        if it >= min_iterations and abs(lam - history[-11]) <= rtol * abs(lam):
            break
    return lam, it


class CentralDifference:
    """Central-difference integrator with lumped mass, Dirichlet DOFs and Rayleigh damping.

    Parameters
    ----------
    stiffness
        Stiffness matrix K (N/m), scipy sparse (n, n).
    mass
        Lumped mass per DOF (kg), (n,), all > 0.
    fixed_dofs
        Indices of Dirichlet DOFs (held at zero unless :meth:`prescribe` says otherwise).
    rayleigh_alpha, rayleigh_beta
        Damping ``C = alpha M + beta K``; alpha in 1/s, beta in s.
    safety_factor
        Factor (0, 1] on the critical step in :meth:`stable_time_step`.
    max_eigenvalue
        A known ``omega_max^2`` (1/s^2) of the constrained ``M^-1 K``, to skip the power iteration.

    Attributes
    ----------
    k_op
        ``K`` as a :class:`~pdfem.fem.node_blocks.NodeBlockOperator`: ``k_op @ x`` is
        ``K @ x``, bit for bit, faster.
    u, v, a
        Displacement (m), velocity (m/s), acceleration (m/s^2) DOF vectors at ``time``.
    v_half
        Mid-step velocity of the last step (m/s).
    f_ext
        External force (N) of the last step.
    time
        Current time (s).
    """

    def __init__(self, stiffness: sp.spmatrix, mass: np.ndarray, fixed_dofs=None,
                 rayleigh_alpha: float = 0.0, rayleigh_beta: float = 0.0,
                 safety_factor: float = 0.9, max_eigenvalue: float | None = None):
        self.K = sp.csr_matrix(stiffness)
        self.k_op = NodeBlockOperator(self.K)   # K x by node blocks: the bits of self.K @ x
        self.m = np.asarray(mass, dtype=np.float64).copy()
        n = self.m.shape[0]
        if self.K.shape != (n, n):
            raise ValueError(f"stiffness {self.K.shape} and mass ({n},) do not match")
        if not np.all(self.m > 0.0):
            raise ValueError("every lumped mass must be strictly positive")
        if not 0.0 < safety_factor <= 1.0:
            raise ValueError(f"safety_factor must lie in (0, 1] (got {safety_factor!r})")
        if rayleigh_alpha < 0.0 or rayleigh_beta < 0.0:
            raise ValueError("Rayleigh damping coefficients must be >= 0")
        self.n = n
        self.alpha = float(rayleigh_alpha)
        self.beta = float(rayleigh_beta)
        self.safety_factor = float(safety_factor)
        self.fixed = np.unique(np.asarray([] if fixed_dofs is None else fixed_dofs, dtype=np.int64))
        if self.fixed.size and (self.fixed[0] < 0 or self.fixed[-1] >= n):
            raise ValueError("fixed DOF index out of range")
        self.free = np.ones(n, dtype=bool)
        self.free[self.fixed] = False
        self._prescribed: Prescribed | np.ndarray | None = None
        self._lam = None if max_eigenvalue is None else float(max_eigenvalue)
        self.power_iterations = 0
        self.u = np.zeros(n)
        self._ku = np.zeros(n)                  # K u of the state (kept from the step)
        self._pair: NodeBlockPair | None = None  # K and a companion matrix, applied together
        self._cu: np.ndarray | None = None      # the companion's product with u
        self.v = np.zeros(n)
        self.a = np.zeros(n)
        self.v_half = np.zeros(n)
        self.f_ext = np.zeros(n)
        self.f_damp = np.zeros(n)
        self._zero = np.zeros(n)
        self._zero.flags.writeable = False
        self.time = 0.0
        self.last_dt = 0.0
        self.work_external = 0.0
        self.work_supports = 0.0
        self.damping_dissipated = 0.0
        self._reaction = np.zeros(self.fixed.size)
        self._held = np.zeros(self.fixed.size)   # the displacement of supports held still
        self._started: StepStart | None = None   # a step begun (begin_step), not yet ended

    def distribute(self, comm) -> None:
        """Nothing to share over the ranks of ``comm``: an explicit step is a few products per
        DOF, done on every rank (:meth:`pdfem.fem.base.Structure.distribute`)."""

    # ----------------------------------------------------------------- constraints
    def prescribe(self, values: np.ndarray | Prescribed | None) -> None:
        """Prescribe the displacement (m) of the fixed DOFs.

        Parameters
        ----------
        values
            ``None`` (zero), an array with one value per fixed DOF (in the sorted order of
            ``self.fixed``), or a callable ``t -> array`` for a time-dependent displacement.
        """
        if values is not None and not callable(values):
            values = np.asarray(values, dtype=np.float64).reshape(-1)
            if values.shape != self.fixed.shape:
                raise ValueError(f"need {self.fixed.size} prescribed values, got {values.size}")
        self._prescribed = values

    def _dirichlet(self, t: float) -> np.ndarray:
        if self._prescribed is None:
            return np.zeros(self.fixed.size)
        if callable(self._prescribed):
            return np.asarray(self._prescribed(t), dtype=np.float64).reshape(self.fixed.shape)
        return self._prescribed

    # ----------------------------------------------------------------- stable step
    def max_eigenvalue(self) -> float:
        """``omega_max^2`` (1/s^2) of the constrained ``M^-1 K`` (power iteration, cached)."""
        if self._lam is None:
            self._lam, self.power_iterations = power_iteration_max_eigenvalue(
                self.K, self.m, self.free)
        return self._lam

    def set_max_eigenvalue(self, value: float) -> None:
        """Use a known ``omega_max^2`` (1/s^2) instead of the power iteration."""
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"eigenvalue must be positive and finite (got {value!r})")
        self._lam = float(value)

    def critical_time_step(self) -> float:
        """Critical step (s): ``2/omega_max``, reduced for Rayleigh damping of the highest mode."""
        lam = self.max_eigenvalue()
        if lam <= 0.0:
            return math.inf
        w = math.sqrt(lam)
        xi = 0.5 * self.alpha / w + 0.5 * self.beta * w
        # 2/w (sqrt(1 + xi^2) - xi) without its cancellation (and xi^2's overflow): heavy
        # damping gives a small step, not inf; an overflowed lam (inf) gives 0 or NaN
        return 2.0 / (w * (math.hypot(1.0, xi) + xi))

    def stable_time_step(self) -> float:
        """Safety factor times :meth:`critical_time_step` (s)."""
        return self.safety_factor * self.critical_time_step()

    # ----------------------------------------------------------------- stepping
    def _damping_force(self, v: np.ndarray) -> np.ndarray:
        if self.alpha and self.beta:
            return self.alpha * self.m * v + self.beta * (self.k_op @ v)
        if self.alpha:
            return self.alpha * self.m * v
        if self.beta:
            return self.beta * (self.k_op @ v)
        return self._zero

    def initialize(self, u: np.ndarray | None = None, v: np.ndarray | None = None,
                   f_ext: np.ndarray | None = None, time: float = 0.0) -> None:
        """Set the state at ``time`` and compute the consistent initial acceleration.

        Parameters
        ----------
        u, v
            Initial displacement (m) and velocity (m/s) DOF vectors (default zero); the Dirichlet
            DOFs are overwritten with their prescribed displacement and zero velocity.
        f_ext
            External force (N) at ``time`` (default zero).
        time
            Start time (s).
        """
        self.time = float(time)
        self.u = np.zeros(self.n) if u is None else np.array(u, dtype=np.float64)
        self.v = np.zeros(self.n) if v is None else np.array(v, dtype=np.float64)
        self.u[self.fixed] = self._dirichlet(self.time)
        self.v[self.fixed] = 0.0
        self.v_half = self.v.copy()
        self.f_ext = np.zeros(self.n) if f_ext is None else np.array(f_ext, dtype=np.float64)
        self.f_damp = self._damping_force(self.v)
        self._ku, self._cu = self._products(self.u)
        self.a = (self.f_ext - self._ku - self.f_damp) / self.m
        self.a[self.fixed] = 0.0
        self._reaction = self.residual_force()[self.fixed]

    def step(self, dt: float, f_ext: np.ndarray | None = None) -> None:
        """Advance the state by ``dt`` (s) with the external force ``f_ext`` (N) at the new time:
        :meth:`begin_step`, then :meth:`end_step`.

        Parameters
        ----------
        dt
            Time step (s); stable if below :meth:`critical_time_step`.
        f_ext
            (n,) external force DOF vector at ``time + dt``; default zero.
        """
        self.begin_step(dt)
        self.end_step(f_ext)

    def begin_step(self, dt: float) -> StepStart:
        """The first half of a step of ``dt`` (s): the half kick and the drift to the new
        displacement, and the internal forces there (``K u_new`` and the damping force of the
        mid-step velocity), which need no external force. The state is unchanged until
        :meth:`end_step` (a structure coupled to another body computes the loads of the step's
        end from these first, :mod:`pdfem.motion.attached_frame`)."""
        t_new = self.time + dt
        v_half, u_new = np.empty(self.n), np.empty(self.n)
        moving = self._supports_move
        g = self._dirichlet(t_new) if moving else self._held
        predict(self.u, self.v, self.a, dt, self.fixed, g, v_half, u_new)
        ku, cu = self._products(u_new)
        self._started = StepStart(float(dt), v_half, u_new, self._damping_force(v_half), ku,
                                  cu, moving)
        return self._started

    def end_step(self, f_ext: np.ndarray | None = None) -> None:
        """Finish the step :meth:`begin_step` began, with the external force ``f_ext`` (N, (n,),
        at the step's end; default zero): the accelerations, the second half kick, the works."""
        s, self._started = self._started, None
        n = self.n
        a_new, v_new = np.empty(n), np.empty(n)
        f = self._zero if f_ext is None else np.array(f_ext, dtype=np.float64)
        f_damp_old = self.f_damp
        self.f_damp = s.f_damp
        # Dirichlet DOFs: acceleration from the change of their mid-step velocity (zero when
        # held still)
        correct(f, s.ku, self.f_damp, self.f_damp is not self._zero, self.m, s.dt, s.v_half,
                self.v_half, self.fixed, a_new, v_new)
        # work of each force over the step by the trapezoidal rule on the displacement
        # increment: with it the scheme's energy balance holds exactly (module docstring)
        self._book_work(s.dt * s.v_half, f, f_damp_old, s.ku if s.moving else None, a_new)
        self._advance(s.dt, s.u, s.v_half, a_new, v_new, f)
        self._ku, self._cu = s.ku, s.cu

    def stiffness_force(self) -> np.ndarray:
        """``K u`` (N) of the current state (the step's product, kept; do not change it)."""
        return self._ku

    def add_companion(self, op: NodeBlockOperator) -> None:
        """Form ``op @ u`` with every ``K u``, in the same pass over the blocks when ``op``
        has K's pattern (a spinning structure's geometric stiffness, which its inertial loads
        need every step); :meth:`companion_force` gives it."""
        self._pair = NodeBlockPair(self.k_op, op)
        self._ku, self._cu = self._products(self.u)

    def companion_force(self) -> np.ndarray:
        """``op @ u`` (N) of the current state for the matrix of :meth:`add_companion`."""
        return self._cu

    def _products(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """``K u`` and the companion's product (None without one)."""
        if self._pair is None:
            return self.k_op @ u, None
        return self._pair @ u

    @property
    def _supports_move(self) -> bool:
        """Whether some Dirichlet DOF has a prescribed displacement (its reaction works)."""
        return bool(self.fixed.size) and self._prescribed is not None

    def _advance(self, dt: float, u: np.ndarray, v_half: np.ndarray, a: np.ndarray,
                 v: np.ndarray, f: np.ndarray) -> None:
        """Take the new state at the end of a step of ``dt`` (s)."""
        self.u, self.v_half, self.a, self.v, self.f_ext = u, v_half, a, v, f
        self.time += dt
        self.last_dt = float(dt)

    def _book_work(self, du: np.ndarray, f: np.ndarray, f_damp_old: np.ndarray,
                   ku: np.ndarray | None, a_new: np.ndarray) -> None:
        """Add the step's works by the trapezoidal rule on the displacement increment ``du``
        (with it the energy balance holds exactly): of the external force (old ``f_ext``, new
        ``f``), of the damping (old and new ``f_damp``) and, given the new ``K u`` as ``ku``
        (moving supports), of the support reactions."""
        if f.any() or self.f_ext.any():  # else the work is +-0 (the same sum, no passes)
            self.work_external += trapezoid_work(self.f_ext, f, du, NO_OFFSET)
        if self.f_damp is not self._zero:
            self.damping_dissipated += trapezoid_work(f_damp_old, self.f_damp, du, NO_OFFSET)
        if ku is not None:
            fx = self.fixed
            reaction = ku[fx] + self.f_damp[fx] + self.m[fx] * a_new[fx] - f[fx]
            self.work_supports += 0.5 * float((self._reaction + reaction) @ du[fx])
            self._reaction = reaction

    steps_before_contact = False
    """Whether a step is taken before the contacts over it and amended by their impulses
    (:class:`pdfem.fem.implicit.Newmark`), rather than after them (here: the impulses jump
    the velocity at the substep's start)."""

    def contact_impulse(self, dofs: np.ndarray, impulse: np.ndarray) -> float:
        """Contact impulses ``impulse`` (N s) on the DOFs ``dofs`` (distinct) now, as a velocity
        jump (:meth:`apply_impulse`); their work (J), the kinetic-energy change
        ``v . J + J^2 / (2 m)`` (zero on Dirichlet DOFs)."""
        j = np.asarray(impulse, dtype=np.float64)
        free = self.free[dofs]
        work = float(np.sum((self.v[dofs] * j + 0.5 * j * j / self.m[dofs])[free]))
        self.apply_impulse(dofs, j)
        return work

    def apply_impulse(self, dofs: np.ndarray, impulse: np.ndarray) -> None:
        """Give the DOFs ``dofs`` the impulses ``impulse`` (N s) now: their velocity jumps by
        impulse / mass (an impulse on a Dirichlet DOF goes to its support)."""
        dv = np.asarray(impulse, dtype=np.float64) / self.m[dofs]
        dv[~self.free[dofs]] = 0.0
        np.add.at(self.v, dofs, dv)

    def kinetic_correction(self) -> float:
        """``-(dt^2 / 8) a . M a`` (J), dt the last step: added to ``1/2 v . M v`` it gives the
        kinetic energy the scheme conserves exactly, ``1/2 v_half(n-1/2) . M v_half(n+1/2)``.
        It is bounded and vanishes as dt -> 0; the highest modes carry most of it."""
        return -0.125 * self.last_dt ** 2 * float(self.a @ (self.m * self.a))

    STATE_ARRAYS = ("u", "v", "a", "v_half", "f_ext", "f_damp")
    """Names of the DOF vectors of the state (:meth:`checkpoint_state`)."""
    STATE_SCALARS = ("time", "last_dt", "work_external", "work_supports", "damping_dissipated")
    """Names of the scalars of the state."""

    def checkpoint_state(self) -> dict[str, np.ndarray | float]:
        """Copies of the state arrays (:data:`STATE_ARRAYS`) and scalars (:data:`STATE_SCALARS`:
        time and last step (s), the accumulated works and damping loss (J)), for a checkpoint."""
        out: dict[str, np.ndarray | float] = {k: getattr(self, k).copy() for k in self.STATE_ARRAYS}
        out.update({k: getattr(self, k) for k in self.STATE_SCALARS})
        return out

    def restore_state(self, state: dict) -> None:
        """Restore a state from :meth:`checkpoint_state` exactly (a restarted run continues bit for bit)."""
        for k in self.STATE_ARRAYS:
            a = np.array(state[k], dtype=np.float64)
            if a.shape != (self.n,):
                raise ValueError(f"state {k!r} has shape {a.shape}, expected ({self.n},)")
            setattr(self, k, a)
        if not (self.alpha or self.beta):
            self.f_damp = self._zero  # as _damping_force gives it, so step() skips it
        for k in self.STATE_SCALARS:
            setattr(self, k, float(state[k]))
        self._ku, self._cu = self._products(self.u)
        self._reaction = self.residual_force()[self.fixed]

    def residual_force(self) -> np.ndarray:
        """``K u + C v_half + M a - f_ext`` (N) per DOF: zero on free DOFs, the support reaction
        (the force the support exerts on the body) on Dirichlet DOFs."""
        return self.stiffness_force() + self.f_damp + self.m * self.a - self.f_ext
