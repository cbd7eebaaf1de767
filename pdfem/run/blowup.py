"""Blow-up detection: stop a run whose state became unphysical, with a diagnosis.

Three checks, each cheap enough to leave on:

- **runaway motion and NaN/Inf** (:meth:`BlowupMonitor.check_motion`, every
  ``run.stability_check_interval_steps`` coupling steps): for each ice body the largest
  particle speed times the ice step, ``max |v| h``, must stay below the horizon ``delta`` (a
  particle crossing its whole family in one step has left the regime the step was chosen for),
  and the positions and velocities must be finite. Two numpy reductions over (N, 3) arrays, no
  kernel. (Elastic structures check their own displacement every step.)
- **energy growth without work input** (:meth:`BlowupMonitor.check_energy`, at every output
  frame): the total energy (kinetic + strain + gravity + structures + short-range potential)
  minus what was put in (initial energy + work of constraints, rigid bodies, loads and moving
  supports) plus what was dissipated (contact, fracture, damping) is the energy *created*; it
  must stay below ``ENERGY_GROWTH_LIMIT`` times the energy supplied plus a round-off floor, the elastic energy of a uniform strain ``FLOOR_STRAIN`` in every body
  (``sum 1/2 E V FLOOR_STRAIN^2``: a run at rest has energies of 1e-25 J that round-off alone
  can multiply).
  It is minus the residual of the balance (:mod:`pdfem.run.energy`, every term computed on its
  own): near zero (round-off and the O(dt^2) energy error of the explicit schemes) in a
  healthy run, growing exponentially in an unstable one.
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

ENERGY_GROWTH_LIMIT = 1.0
"""Energy created (J) above this multiple of the energy supplied (J) stops the run: the total
energy has doubled with nothing doing work on the system."""


FLOOR_STRAIN = 1e-5
"""Strain whose elastic energy over the bodies is the absolute floor of the energy check."""


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
    """

    def __init__(self, bodies: list, ice_step: float, stable_steps: dict[str, float],
                 check_interval: int = 10, energy_check: bool = True):
        if check_interval < 1:
            raise ValueError(f"check_interval must be >= 1, got {check_interval}")
        self.bodies = list(bodies)
        self.ice_step = float(ice_step)
        self.stable_steps = dict(stable_steps)
        self.check_interval = int(check_interval)
        self.energy_check = bool(energy_check)
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

    def check_energy(self, t: float, step: int, created: float, supplied: float) -> None:
        """At an output frame: the energy created (J) against the energy supplied (J).

        Raises
        ------
        InstabilityError
            If ``created > ENERGY_GROWTH_LIMIT * max(supplied, 0) + energy_floor``, or the
            energies are not finite.
        """
        if not self.energy_check:
            return
        if not (math.isfinite(created) and math.isfinite(supplied)):
            raise InstabilityError(f"the energy of the run became NaN/Inf at t = {t:.6e} s "
                                   f"(step {step:,}); " + self._fix(self._worst()))
        if created > ENERGY_GROWTH_LIMIT * max(supplied, 0.0) + self.energy_floor:
            name = self._worst()
            raise InstabilityError(
                f"energy grew without work input at t = {t:.6e} s (step {step:,}): "
                f"{created:.3e} J created against {supplied:.3e} J supplied (initial energy + "
                f"work of constraints, rigid bodies, loads and supports); the fastest particles are in ice body "
                f"'{name}'; {self._fix(name)}")

    def _worst(self) -> str:
        """Name of the body with the fastest particle (the likely seat of the instability)."""
        if not self.bodies:
            return ""
        speeds = [float(np.nan_to_num(np.einsum("ij,ij->i", b.v, b.v), nan=np.inf).max())
                  if b.n else 0.0 for b in self.bodies]
        return self.bodies[int(np.argmax(speeds))].name
