"""Bar wave speed from the free end of a fixed-free ice bar (``bar_wave_speed.toml``).

The bar moves at v along its axis when its end x = 0 is held. Its free end at x = L then
passes through its start position at t1 = 2L/c and again at t2 = 4L/c (1-D wave equation), so
the measured speed is c = 2L / (t2 - t1), L the free length from the held end to the free face.
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


def _free_end(outcome: Outcome) -> tuple[np.ndarray, np.ndarray, float]:
    """Frame times (s), mean axial displacement of the free end layer (m), free length L (m)."""
    bar = outcome.data["ice"]["bar"]
    dx = outcome.case.ice[0].dx
    x = bar["x0"][:, 0]
    end = x > x.max() - 0.5 * dx
    return outcome.data["time"], bar["u"][:, end, 0].mean(axis=1), float(x.max() + 0.5 * dx)


def measure(outcome: Outcome) -> float:
    """c = 2L / (t2 - t1) from the free end's first two returns to its start position (m/s)."""
    t, w, length = _free_end(outcome)
    crossings = zero_crossings(t, w)
    if len(crossings) < 2:
        raise ValueError(f"the free end crossed its start position {len(crossings)} times; need 2")
    return 2.0 * length / (crossings[1] - crossings[0])


def reference(case: Case) -> float:
    """Bar wave speed sqrt(E / rho) of the ice (m/s)."""
    m = case.ice[0].material
    return math.sqrt(m.youngs_modulus / m.density)


def quick(case: Case) -> Case:
    """Half the length (0.5 m) and a 0.08 m section (8 x 8 particles): a quarter of the
    particles for half the time."""
    box = case.ice[0].shape
    side = 8 * case.ice[0].dx
    shape = Box(tuple(box.min), (0.5, side, side))
    return replace_run(replace_ice(case, shape=shape), end_time=1.1e-3)


def plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Free-end displacement against the fixed-free bar of the 1-D wave equation."""
    t, w, length = _free_end(outcome)
    v0 = outcome.case.ice[0].initial_velocity[0]
    period = 4.0 * length / ref
    phase = np.mod(t, period) / period  # a triangle wave of amplitude v L / c
    theory = v0 * period * np.where(phase < 0.5, 0.25 - np.abs(phase - 0.25), -0.25 + np.abs(phase - 0.75))
    ax = fig.add_subplot()
    ax.plot(t * 1e3, w * 1e6, "o-", ms=3, label=f"pdfem (c = {value:.0f} m/s)")
    ax.plot(t * 1e3, theory * 1e6, "k--", label=f"1-D wave theory (c = {ref:.0f} m/s)")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("free-end displacement [µm]")
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.legend()


CASES = (
    ValidationCase(
        name="wave_speed", case_file="bar_wave_speed.toml", quantity="wave speed in a bar", unit="m/s",
        measure=measure, reference=reference, plot=plot, quick=quick, tolerance=0.03,
        source="1-D wave equation, c = sqrt(E/rho); fixed-free bar, free end back at its start "
               "at t = 2L/c and 4L/c (Graff, Wave Motion in Elastic Solids, 1975, ch. 2)",
        quick_note="0.5 m bar of 8 x 8 particles instead of 1.0 m of 12 x 12, run to 1.1 ms"),
)
