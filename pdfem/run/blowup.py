"""Blow-up detection: stop a run whose state became unphysical, with a diagnosis.

Three checks, each cheap enough to leave on:

- **runaway motion and NaN/Inf** (:meth:`BlowupMonitor.check_motion`, every
  ``run.stability_check_interval_steps`` coupling steps): for each ice body the largest
  particle speed times the ice step, ``max |v| h``, must stay below the horizon ``delta`` (a
  particle crossing its whole family in one step has left the regime the step was chosen for),
  and the positions and velocities must be finite. Two numpy reductions over (N, 3) arrays, no
  kernel. (Elastic structures check their own displacement every step.)
- **energy created** (:meth:`BlowupMonitor.check_energy`, every check interval and at every
  output frame): the energy *created* is minus the residual of the balance
  (:mod:`pdfem.run.energy`: supplied - stored - dissipated, every term computed on its own,
  velocity Verlet's and the central difference's own kinetic shares included) plus the
  negative part of every dissipation term (contact, fracture and damping can only take energy
  out; a negative one created it). The *limit* is ``run.energy_tolerance`` (a fraction,
  default 0.01) of the energy supplied (initial energy + work of constraints, rigid bodies,
  loads and moving supports, J) plus a round-off floor, the elastic energy of a uniform strain
  ``FLOOR_STRAIN`` in every body (``sum 1/2 E V FLOOR_STRAIN^2``: a run at rest has energies
  of 1e-25 J that round-off alone can multiply). Crossing the limit is not yet a stop, since
  an event such as the onset of crushing creates its O(dt^2) share at once while little energy
  has been supplied (edge crushing: 0.088 J at 3.6 J supplied, 1.55 %, whose share falls below
  1 % within 1.8 ms as the push goes on and creates no more). The run stops when, after the
  crossing, the created energy

  - grows by more than the tolerance of the energy supplied since then (plus the floor):
    steady creation (:data:`GROWTH`);
  - or stays above the limit while the supply does not grow by the tolerance: nothing will
    dilute it, a lasting error (a coarse cube struck at 1.5 x the stable step keeps 1.5 %);
  - or, at any check, exceeds :data:`GROSS` times the limit: no transient is that large;
  - or is above the limit through a negative dissipation term, which stops at once.

  Above the stable step estimate (``run.allow_unstable_time_step``) nothing guarantees
  stability but this check, so the tolerance is halved (:data:`ABOVE_ESTIMATE`). Measured
  (docs/ice_failure.md, "Energy guard"): every ``models/`` case and the coupled validation
  entries at their steps create at most 0.23 % of the energy supplied (the demo at 0.8 x the
  stable step) apart from crushing onsets; the demo at 1.5 x keeps creating (0.87 % at
  2.6 ms) and stops at 2.41 ms.
- NaN/Inf anywhere else (short-range contact search) is turned into the same error.

A failed check raises :class:`pdfem.errors.InstabilityError` (exit 3) naming the body, the
particle and its reference position (m), the time (s) and step, the quantity, and a fix
(usually a smaller step: ``run.time_step`` or ``run.safety_factor``), with the ratio of the
step used to the stable estimate.
"""

from __future__ import annotations

import math

import numpy as np

from pdfem.errors import InstabilityError
from pdfem.run.energy import budget_text

DISSIPATION_TERMS = ("contact_dissipated", "fracture_dissipated", "damping_dissipated")
"""Energy-row keys of the dissipation terms, each >= 0 in a correct run (J)."""


FLOOR_STRAIN = 1e-5
"""Strain whose elastic energy over the bodies is the absolute floor of the energy check."""

GROSS = 10.0
"""Created energy above this many times the limit stops the run at once (-)."""

ABOVE_ESTIMATE = 0.5
"""Factor on the tolerance when the ice step is above its stable estimate (-)."""


class BlowupMonitor:
    """The checks of the module docstring for one run.

    Parameters
    ----------
    bodies
        The ice bodies (``name``, ``y``, ``v``, ``x0``, ``delta``).
    ice_step
        The ice (sub)step h (s).
    stable_steps
        ``{body name: stable step (s)}``, quoted in the diagnosis.
    check_interval
        Coupling steps between motion checks (>= 1).
    energy_check
        Whether :meth:`check_energy` applies (False when some work input is not counted).
    energy_tolerance
        Energy created allowed, as a fraction of the energy supplied (-), above the round-off
        floor (``run.energy_tolerance``).
    """

    def __init__(self, bodies: list, ice_step: float, stable_steps: dict[str, float],
                 check_interval: int = 10, energy_check: bool = True,
                 energy_tolerance: float = 0.01):
        if check_interval < 1:
            raise ValueError(f"check_interval must be >= 1, got {check_interval}")
        self.bodies = list(bodies)
        self.ice_step = float(ice_step)
        self.stable_steps = dict(stable_steps)
        self.check_interval = int(check_interval)
        self.energy_check = bool(energy_check)
        self.energy_tolerance = float(energy_tolerance)
        above = any(self.ice_step > s for s in self.stable_steps.values() if math.isfinite(s))
        self.tolerance = self.energy_tolerance * (ABOVE_ESTIMATE if above else 1.0)
        self._crossed: tuple[float, float] | None = None  # (created, supplied) at the crossing
        self.energy_floor = sum(0.5 * b.material.youngs_modulus * float(b.vol.sum())
                                * FLOOR_STRAIN ** 2 for b in self.bodies)  # J

    def _fix(self, name: str) -> str:
        stable = self.stable_steps.get(name, math.inf)
        ratio = (f"the ice step {self.ice_step:.3e} s is {self.ice_step / stable:.2f} x the "
                 f"stable estimate {stable:.3e} s of this body; "
                 if math.isfinite(stable) and stable > 0 else "")
        return (ratio + "use a smaller step: lower run.time_step (or run.safety_factor when the "
                "step is automatic), and check loads and contact for sudden impulses")

    def check_motion(self, t: float, step: int, force: bool = False) -> None:
        """Every ``check_interval`` steps (or when ``force``): speeds and finiteness.

        Raises
        ------
        InstabilityError
            If a particle moves more than a horizon in one step, or a position or velocity is
            NaN or infinite.
        """
        if not force and step % self.check_interval:
            return
        for b in self.bodies:
            speed2 = np.einsum("ij,ij->i", b.v, b.v)
            top = float(speed2.max()) if speed2.size else 0.0
            finite_y = math.isfinite(float(b.y.sum()))
            limit = b.delta / self.ice_step
            if finite_y and top <= limit * limit:
                continue
            bad = ~np.isfinite(speed2) | ~np.isfinite(b.y).all(axis=1)
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                what = (f"the position or velocity of {int(bad.sum()):,} particles became NaN/Inf "
                        f"(the first: particle {i}")
            else:
                i = int(np.argmax(speed2))
                what = (f"particle {i} moves {math.sqrt(top) * self.ice_step:.3e} m per step, "
                        f"more than the horizon {b.delta:.3e} m (speed {math.sqrt(top):.3e} m/s")
            raise InstabilityError(
                f"ice body '{b.name}' became unstable at t = {t:.6e} s (step {step:,}): {what}, "
                f"reference position {np.round(b.x0[i], 6).tolist()} m); {self._fix(b.name)}")

    def due(self, step: int) -> bool:
        """Whether ``step`` is a check step (every ``check_interval`` coupling steps)."""
        return step % self.check_interval == 0

    def check_energy(self, t: float, step: int, row: dict[str, float]) -> None:
        """The energy balance ``row`` (:meth:`pdfem.run.energy.EnergyBalance.row`, J): the
        energy created against the energy supplied.

        Raises
        ------
        InstabilityError
            If the energy created exceeds ``energy_tolerance * max(supplied, 0) + energy_floor``
            or the energies are not finite; the message lists the terms.
        """
        if not self.energy_check:
            return
        supplied, residual = row["supplied"], row["residual"]
        negative = {k: -row[k] for k in DISSIPATION_TERMS if row.get(k, 0.0) < 0.0}
        created = -residual + sum(negative.values())
        if not (math.isfinite(created) and math.isfinite(supplied)):
            raise InstabilityError(f"the energy of the run became NaN/Inf at t = {t:.6e} s "
                                   f"(step {step:,}); " + self._fix(self._worst()))
        limit = self.tolerance * max(supplied, 0.0) + self.energy_floor
        if created <= limit:
            self._crossed = None
            return
        why = (self._verdict(created, supplied, limit) if sum(negative.values()) <= limit else
               "a dissipation term is negative (a transient cannot excuse that)")
        if why is None:
            return
        name = self._worst()
        share = f" = {100 * created / supplied:.2f} %" if supplied > 0 else ""
        parts = [f"residual {residual:.4g} J (supplied - stored - dissipated)"]
        parts += [f"{k} {-v:.4g} J (negative: dissipation cannot create energy)"
                  for k, v in negative.items()]
        halved = (f" (run.energy_tolerance = {self.energy_tolerance:g} halved: the step is "
                  "above its stable estimate)" if self.tolerance < self.energy_tolerance else
                  f" (run.energy_tolerance = {self.energy_tolerance:g})")
        raise InstabilityError(
            f"the run created energy at t = {t:.6e} s (step {step:,}): {created:.4g} J{share} of "
            f"the {supplied:.4g} J supplied, above the tolerance {self.tolerance:g} of it"
            f"{halved} + round-off floor {self.energy_floor:.2g} J, and {why}; "
            f"{'; '.join(parts)}. Energy budget:\n{budget_text(row)}\nThe fastest particles "
            f"are in ice body '{name}'; {self._fix(name)}; or, if an energy error of this size "
            "is acceptable for the case, raise run.energy_tolerance")

    def _verdict(self, created: float, supplied: float, limit: float) -> str | None:
        """Why created energy above ``limit`` (J) stops the run, or None while it may be a
        transient (see the module docstring); remembers the first crossing."""
        tol, floor = self.tolerance, self.energy_floor
        if created > GROSS * limit:
            return f"more than {GROSS:g} x the limit (no transient is that large)"
        if self._crossed is None:
            self._crossed = (created, supplied)
            return None
        created0, supplied0 = self._crossed
        if created - created0 > tol * max(supplied - supplied0, 0.0) + floor:
            return (f"it keeps growing: {created - created0:.4g} J more since it crossed the "
                    f"limit, while {supplied - supplied0:.4g} J were supplied")
        if supplied - supplied0 <= tol * max(supplied0, 0.0):
            return ("it lasts: no energy supplied since it crossed the limit would dilute it "
                    "(a lasting error, not a transient)")
        return None

    def _worst(self) -> str:
        """Name of the body with the fastest particle (the likely seat of the instability)."""
        if not self.bodies:
            return ""
        speeds = [float(np.nan_to_num(np.einsum("ij,ij->i", b.v, b.v), nan=np.inf).max())
                  if b.n else 0.0 for b in self.bodies]
        return self.bodies[int(np.argmax(speeds))].name
