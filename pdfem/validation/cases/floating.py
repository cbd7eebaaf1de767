"""Floating ice (``floating_draught.toml``, ``floating_heave.toml``): the hydrostatic draught
of a sheet and the free heave period of a block, buoyancy from :class:`pdfem.forces.water.Water`.

Both are measured from the ice's volume-weighted mean height z_c (m) at every frame. The
draught is ``level - (z_c - h/2)`` averaged over the last fifth of the run (the sheet has
settled under linear drag); its reference is Archimedes' ``d = (rho_ice / rho_water) h``. The
heave period is twice the mean spacing of the crossings of z_c through the middle of its swing;
its reference is the period of the mass ``rho_ice h A`` on the hydrostatic spring
``rho_water g A`` (linear while the water line stays on the block's sides, no added mass):
``T = 2 pi sqrt(rho_ice h / (rho_water g))``. SI units.

Measured (``pdfem validate --case floating_draught --case floating_heave_period``):
draught 0.0878012 m against 0.0878049 m (-0.004 %), heave period 0.939904 s against
0.939885 s (+0.002 %); ``--quick``: 0.087838 m (+0.04 %, run to 1.2 s) and the same period.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from pdfem.case import Case
from pdfem.geometry.shapes import Box
from pdfem.validation.case import Outcome, ValidationCase, replace_ice, replace_run
from pdfem.validation.measure import zero_crossings

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _thickness(case: Case) -> float:
    """The ice box's thickness h (m)."""
    box = case.ice[0].shape
    return float(box.max[2] - box.min[2])


def mean_height(outcome: Outcome) -> tuple[np.ndarray, np.ndarray]:
    """Frame times (s) and the ice's volume-weighted mean height z_c (m)."""
    body = outcome.data["ice"][outcome.case.ice[0].name]
    z = body["x0"][None, :, 2] + body["u"][:, :, 2]
    w = body["volume"] / body["volume"].sum()
    return outcome.data["time"], z @ w


def draught(outcome: Outcome) -> float:
    """Mean draught (m) over the last fifth of the run: level - (z_c - h/2)."""
    t, zc = mean_height(outcome)
    late = t >= t[0] + 0.8 * (t[-1] - t[0])
    bottom = zc[late].mean() - 0.5 * _thickness(outcome.case)
    return float(outcome.case.water.level - bottom)


def draught_reference(case: Case) -> float:
    """Archimedes: d = (rho_ice / rho_water) h (m)."""
    return case.ice[0].material.density / case.water.density * _thickness(case)


def heave_period(outcome: Outcome) -> float:
    """Twice the mean spacing of z_c's crossings through the middle of its swing (s)."""
    t, zc = mean_height(outcome)
    crossings = zero_crossings(t, zc - 0.5 * (zc.max() + zc.min()))
    if len(crossings) < 3:
        raise ValueError(f"the block crossed its mean height {len(crossings)} times; need 3")
    return float(2.0 * (crossings[-1] - crossings[0]) / (len(crossings) - 1))


def heave_reference(case: Case) -> float:
    """T = 2 pi sqrt((1 + Ca) rho_ice h / (rho_water g)) (s); Ca = water.added_mass (0 in the
    case file: the added mass of the submerged volume, Ca rho_w d A = Ca rho_i h A)."""
    g = -case.run.gravity[2]
    mass = (1.0 + case.water.added_mass) * case.ice[0].material.density * _thickness(case)
    return 2.0 * math.pi * math.sqrt(mass / (case.water.density * g))


def _smaller(case: Case, side: float, end_time: float) -> Case:
    """The case with a ``side`` x ``side`` ice box (m), run to ``end_time`` (s)."""
    box = case.ice[0].shape
    shape = Box(tuple(box.min), (box.min[0] + side, box.min[1] + side, box.max[2]))
    return replace_run(replace_ice(case, shape=shape), end_time=end_time)


def draught_quick(case: Case) -> Case:
    """A 0.2 m x 0.2 m sheet (8 x 8 x 4 particles), run to 1.2 s."""
    return _smaller(case, 0.2, 1.2)


def heave_quick(case: Case) -> Case:
    """A 0.3 m x 0.3 m block (6 x 6 x 5 particles), run to 2.0 s (two periods)."""
    return _smaller(case, 0.3, 2.0)


def _plot(fig: Figure, outcome: Outcome, line: float, label: str) -> None:
    t, zc = mean_height(outcome)
    ax = fig.add_subplot()
    ax.plot(t, zc * 1e3, "o-", ms=2, label="pdfem: mean height of the ice")
    ax.axhline(line * 1e3, color="k", ls="--", label=label)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("mean height z_c [mm]")
    ax.legend()


def plot_draught(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Mean height against the height at Archimedes' draught."""
    case = outcome.case
    _plot(fig, outcome, case.water.level - ref + 0.5 * _thickness(case),
          f"draught d = {ref * 1e3:.2f} mm (Archimedes)")


def plot_heave(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Mean height of the heaving block around its equilibrium."""
    case = outcome.case
    _plot(fig, outcome, case.water.level - draught_reference(case) + 0.5 * _thickness(case),
          f"equilibrium; T = {value:.4f} s measured, {ref:.4f} s analytic")


CASES = (
    ValidationCase(
        name="floating_draught", case_file="floating_draught.toml",
        quantity="draught of a floating ice sheet", unit="m",
        measure=draught, reference=draught_reference, plot=plot_draught, quick=draught_quick,
        tolerance=0.01,
        source="Archimedes' principle: d = (rho_ice / rho_water) h",
        quick_note="0.2 m x 0.2 m sheet (8 x 8 x 4 particles) instead of 0.4 m, run to 1.2 s"),
    ValidationCase(
        name="floating_heave_period", case_file="floating_heave.toml",
        quantity="free heave period of a floating ice block", unit="s",
        measure=heave_period, reference=heave_reference, plot=plot_heave, quick=heave_quick,
        tolerance=0.05,
        source="mass rho_i h A on the hydrostatic spring rho_w g A, no added mass: "
               "T = 2 pi sqrt(rho_i h / (rho_w g)) (e.g. Newman, Marine Hydrodynamics, 1977, "
               "sec. 6.16, with the added mass set to zero)",
        quick_note="0.3 m x 0.3 m block (6 x 6 x 5 particles) instead of 0.5 m, run to 2.0 s"),
)
