"""Energy and angular momentum of a blade held at constant speed by its shaft while it strikes
an ice block (``shaft_energy.toml``; docs/rotating_structures.md, "Shaft and blade loads").

From the history ``shaft/bar`` (every coupling step, :mod:`pdfem.motion.shaft_loads`):

* energy: the work of the shaft (its torque through the clamped root, and the Rayleigh mass
  damping it drives, on the frame's velocity) plus the work of the ice's contact impulses (on
  the blade's true velocity) equals the change of the blade's energy (true kinetic energy
  ``1/2 sum m |v|^2`` with the lumped mass, plus strain energy) plus the damping dissipation:
  ``W_shaft + W_ice = dE + D``;
* angular momentum about the shaft axis: the shaft's angular impulse minus the ice's (the ice
  torque counts positive against the rotation) equals the change of the blade's angular
  momentum ``sum m (x - c) x v . n``: ``H_shaft - H_ice = dL``.

Measured: each balance's residual at the end of the run over the shaft's work (angular impulse),
reference 0, tolerance 0.01 (1 %). Both balances are Newton's laws for the lumped-mass blade,
the reference being exact conservation (e.g. Goldstein, Classical Mechanics, 1980, ch. 1); the
explicit scheme integrates forces into momentum by the trapezoid rule, which the shaft's
integrals use as well. SI units: J, N m s.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pdfem.case import Case
from pdfem.validation.case import Outcome, ValidationCase, unchanged

if TYPE_CHECKING:
    from matplotlib.figure import Figure

HISTORY = "shaft/bar"
"""The shaft history of the case's structure ``bar``."""


def energy_residual(h: dict) -> np.ndarray:
    """(K,) ``W_shaft + W_ice - dE - D`` (J) over the run."""
    return h["shaft_work"] + h["ice_work"] - h["energy_change"] - h["damping_dissipated"]


def momentum_residual(h: dict) -> np.ndarray:
    """(K,) ``H_shaft - H_ice - dL`` (N m s) over the run."""
    return h["shaft_angular_impulse"] - h["ice_angular_impulse"] - h["angular_momentum_change"]


def energy_measure(outcome: Outcome) -> float:
    """The energy balance's residual at the end over the shaft's work (-)."""
    h = outcome.data["histories"][HISTORY]
    return float(energy_residual(h)[-1] / abs(h["shaft_work"][-1]))


def momentum_measure(outcome: Outcome) -> float:
    """The angular-momentum balance's residual at the end over the shaft's angular impulse."""
    h = outcome.data["histories"][HISTORY]
    return float(momentum_residual(h)[-1] / abs(h["shaft_angular_impulse"][-1]))


def zero(case: Case) -> float:
    """0: exact balance."""
    return 0.0


def _plot(fig: Figure, outcome: Outcome, pairs: tuple, unit: str) -> None:
    h = outcome.data["histories"][HISTORY]
    ax = fig.add_subplot()
    for label, y in pairs:
        ax.plot(h["time"] * 1e3, y(h), lw=1.0, label=label)
    ax.set_xlabel("time [ms]")
    ax.set_ylabel(f"[{unit}]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)


def energy_plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Shaft work, ice work, energy change plus dissipation, residual against time."""
    _plot(fig, outcome, (("shaft work", lambda h: h["shaft_work"]),
                         ("ice work", lambda h: h["ice_work"]),
                         ("dE + dissipation",
                          lambda h: h["energy_change"] + h["damping_dissipated"]),
                         ("residual", energy_residual)), "J")


def momentum_plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Angular impulses of shaft and ice, change of angular momentum, residual against time."""
    _plot(fig, outcome, (("shaft angular impulse", lambda h: h["shaft_angular_impulse"]),
                         ("- ice angular impulse", lambda h: -h["ice_angular_impulse"]),
                         ("dL", lambda h: h["angular_momentum_change"]),
                         ("residual", momentum_residual)), "N m s")


SOURCE = ("conservation of energy and of angular momentum about the fixed shaft axis for the "
          "lumped-mass blade (Newton's laws, e.g. Goldstein, Classical Mechanics, 1980, ch. 1)")

def _entries(suffix: str, case_file: str, note: str) -> tuple[ValidationCase, ...]:
    """The energy and angular-momentum entries of ``case_file``, named ``shaft_*<suffix>``."""
    common = dict(case_file=case_file, unit="-", reference=zero, relative=False,
                  tolerance=0.01, source=SOURCE + note, quick=unchanged,
                  quick_note="unchanged (about 10 s)")
    return (
        ValidationCase(name=f"shaft_energy{suffix}", measure=energy_measure, plot=energy_plot,
                       quantity="(W_shaft + W_ice - dE - D) / W_shaft at the end", **common),
        ValidationCase(name=f"shaft_angular_momentum{suffix}", measure=momentum_measure,
                       plot=momentum_plot,
                       quantity="(H_shaft - H_ice - dL) / H_shaft at the end", **common),
    )


CASES = (_entries("", "shaft_energy.toml", "")
         + _entries("_implicit", "shaft_energy_implicit.toml",
                    "; the blade by implicit Newmark steps in its rotating frame, the contact "
                    "impulses amending each step"))
