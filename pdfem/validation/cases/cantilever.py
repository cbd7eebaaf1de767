"""First bending frequency of a clamped steel cantilever (``cantilever_frequency.toml``; the
same beam advanced by implicit Newmark steps, ``cantilever_frequency_implicit.toml`` at 100
steps per period and ``cantilever_frequency_implicit_large_step.toml`` at 10).

A tip load put on at t = 0 and held sets the beam swinging about its static deflection; the
peak of the spectrum of the tip monitor's vertical displacement is the first bending frequency.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from pdfem.case import Case
from pdfem.validation.case import Outcome, ValidationCase, replace_run
from pdfem.validation.measure import spectral_peak, windowed_spectrum

if TYPE_CHECKING:
    from matplotlib.figure import Figure

BETA1_L = 1.875104  # first root of cos(bL) cosh(bL) = -1 (clamped-free beam)


def _tip(outcome: Outcome) -> tuple[np.ndarray, np.ndarray]:
    h = outcome.data["histories"]["monitors/tip"]
    return h["time"], h["u"][:, 2]


def measure(outcome: Outcome) -> float:
    """Peak frequency (Hz) of the tip displacement spectrum."""
    return spectral_peak(*_tip(outcome))


def reference(case: Case) -> float:
    """Euler-Bernoulli f1 = 1.875104^2 / (2 pi L^2) sqrt(E I / (rho A)) of the beam (Hz)."""
    s = case.structures[0]
    length, h, b = s.params["length_x"], s.params["length_z"], s.params["length_y"]
    area, inertia = b * h, b * h**3 / 12.0
    return BETA1_L**2 / (2 * math.pi * length**2) * math.sqrt(s.youngs_modulus * inertia / (s.density * area))


def newmark_reference(case: Case) -> float:
    """The beam's f1 (:func:`reference`) as average-acceleration Newmark steps of
    ``run.time_step`` dt carry it (Hz): ``(2 / dt) atan(w dt / 2) / (2 pi)``, ``w = 2 pi f1``.
    The trapezoidal rule's amplification factor for ``u'' = -w^2 u`` is ``(1 - i w dt / 2) /
    (1 + i w dt / 2)``: modulus 1 (no damping), phase ``2 atan(w dt / 2)`` per step."""
    w, dt = 2.0 * math.pi * reference(case), case.run.time_step
    return 2.0 / dt * math.atan(0.5 * w * dt) / (2.0 * math.pi)


def quick(case: Case) -> Case:
    """Three periods of the first mode instead of six (the same mesh: coarser hexahedra lock)."""
    return replace_run(case, end_time=0.5 * case.run.end_time)


def plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Tip displacement history and its amplitude spectrum."""
    t, w = _tip(outcome)
    ax, bx = fig.subplots(2, 1)
    ax.plot(t * 1e3, w * 1e6, lw=0.9)
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("tip displacement u_z [µm]")
    f, spectrum = windowed_spectrum(t, w)
    keep = f < 4 * ref
    bx.plot(f[keep], spectrum[keep] / spectrum.max(), lw=0.9, label=f"pdfem peak {value:.2f} Hz")
    bx.axvline(ref, color="k", ls="--", label=f"Euler-Bernoulli {ref:.2f} Hz")
    bx.set_xlabel("frequency [Hz]")
    bx.set_ylabel("amplitude (normalised)")
    bx.legend()


SOURCE = ("Euler-Bernoulli cantilever, f1 = 1.875^2/(2 pi L^2) sqrt(EI/(rho A)) "
          "(e.g. Blevins, Formulas for Natural Frequency and Mode Shape, 1979, table 8-1)")


def _entry(name: str, case_file: str, quantity: str, ref=reference,
           source: str = SOURCE) -> ValidationCase:
    """The cantilever entry of ``case_file``: f1 against ``ref``, 3 %."""
    return ValidationCase(
        name=name, case_file=case_file, quantity=quantity, unit="Hz",
        measure=measure, reference=ref, plot=plot, quick=quick, tolerance=0.03, source=source,
        quick_note="3 periods of the first mode (36 ms) instead of 6 (72 ms)")


CASES = (
    _entry("cantilever_frequency", "cantilever_frequency.toml", "cantilever frequency f1"),
    _entry("cantilever_frequency_implicit", "cantilever_frequency_implicit.toml",
           "cantilever frequency f1, implicit structure (T1 / 100 steps)"),
    _entry("cantilever_frequency_implicit_large_step",
           "cantilever_frequency_implicit_large_step.toml",
           "cantilever frequency f1, implicit structure (T1 / 10 steps)", newmark_reference,
           SOURCE + " carried by the average-acceleration rule: (2/dt) atan(w dt/2) "
           "(its amplification factor (1 - i w dt/2)/(1 + i w dt/2))"),
)
