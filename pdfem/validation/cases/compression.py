"""Uniaxial compression of an ice prism (``ice_prism_compression.toml`` at dx = 1 cm and
``ice_prism_compression_fine.toml`` at dx = 5 mm): the peak nominal stress against the
``compressive_strength`` of the "ice" failure law, and the stress that remains after the peak.

The nominal stress is the top platen's force over the prism's section (7 cm x 7 cm; 18 cm long), every
coupling step. Reference: the input strength itself — in a uniaxial stress state the law breaks
the axial bonds exactly at sigma_c (:mod:`pdfem.pd.failure.ice`), so the specimen's measured
strength must equal it at any resolution, as a compression test with lubricated platens
measures a material's strength (e.g. ISO 17892-7 / Timco & Frederking 1990 for sea ice). The
post-peak check asks for a residual strength: crushed ice goes on carrying load (the mean
nominal stress over the last fifth of the run, as a fraction of sigma_c, must be above 0.1);
the localisation check asks that the failure is a band, not the whole gauge length at once.
SI units (Pa, m, s).

Measured (``pdfem validate --case compression_peak --case compression_peak_fine
--case compression_residual --case compression_localisation``): peak 3.20 MPa at dx = 1 cm,
3.13 MPa at dx = 5 mm
(sigma_c = 3 MPa); 0.31 sigma_c after the peak at dx = 1 cm; 4 of the 10 gauge layers broken
(a crushing band one horizon wide at mid-height).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pdfem.case import Case
from pdfem.validation.case import Outcome, ValidationCase, replace_run

if TYPE_CHECKING:
    from matplotlib.figure import Figure

SECTION = 0.07 * 0.07
"""The prism's section (m^2)."""


def _stress(outcome: Outcome) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and nominal compressive stress (Pa, positive) at the top platen."""
    h = outcome.data["histories"]["loads/top"]
    return h["time"], h["force"][:, 2] / SECTION


def peak(outcome: Outcome) -> float:
    """The largest nominal stress of the run (Pa)."""
    return float(_stress(outcome)[1].max())


def residual(outcome: Outcome) -> float:
    """Mean nominal stress over the last fifth of the run, after the peak, over sigma_c (-)."""
    t, s = _stress(outcome)
    late = t >= t[0] + 0.8 * (t[-1] - t[0])
    assert t[np.argmax(s)] < t[late][0], "the peak must come before the last fifth of the run"
    return float(s[late].mean() / _strength(outcome.case))


def localisation(outcome: Outcome) -> float:
    """The fraction of the gauge length (particle layers between the unbreakable end caps)
    whose mean damage at the end of the run exceeds 0.5 (-): a failure that localises in a
    band (or a fault) leaves most of the gauge intact; one that pulverises the whole specimen
    at once gives 1."""
    body = outcome.data["ice"]["prism"]
    x0, damage = body["x0"], body["damage"][-1]
    caps = [r.bounds() for r, _ in outcome.case.ice[0].no_fail]
    z = x0[:, 2]
    gauge = np.ones(len(z), dtype=bool)
    for lo, hi in caps:
        gauge &= ~((z >= lo[2]) & (z <= hi[2]))
    layers = np.unique(z[gauge])
    broken = [damage[gauge & (z == zl)].mean() > 0.5 for zl in layers]
    return float(np.mean(broken))


def _strength(case: Case) -> float:
    return float(case.ice[0].material.compressive_strength)


def plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """The nominal stress history against the compressive strength."""
    t, s = _stress(outcome)
    ax = fig.add_subplot()
    ax.plot(t * 1e3, s / 1e6, lw=0.9, label="pdfem, top platen F / A")
    ax.axhline(_strength(outcome.case) / 1e6, color="k", ls="--", label="compressive_strength")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("nominal stress [MPa]")
    ax.legend()


def _quick(case: Case) -> Case:
    """The run to 3.5 ms: past the peak (about 3 ms)."""
    return replace_run(case, end_time=3.5e-3)


_SOURCE = ("the input compressive_strength: the ice law breaks axial bonds at sigma_c in "
           "uniaxial stress (docs/ice_failure.md); lubricated-platen compression test")
CASES = (
    ValidationCase(
        name="compression_peak", case_file="ice_prism_compression.toml",
        quantity="peak nominal stress, dx = 1 cm", unit="Pa", measure=peak,
        reference=_strength, source=_SOURCE, tolerance=0.10, plot=plot,
        quick_note="unchanged (882 particles, 5 ms)"),
    ValidationCase(
        name="compression_peak_fine", case_file="ice_prism_compression_fine.toml",
        quantity="peak nominal stress, dx = 5 mm", unit="Pa", measure=peak,
        reference=_strength, source=_SOURCE, tolerance=0.10, plot=plot, quick=_quick,
        quick_note="to 3.5 ms (past the peak) instead of 5 ms"),
    ValidationCase(
        name="compression_residual", case_file="ice_prism_compression.toml",
        quantity="stress after the peak / sigma_c, dx = 1 cm", unit="-", measure=residual,
        reference=lambda case: 0.55, relative=False, tolerance=0.45,
        source="crushed ice keeps carrying load: residual strength between 0.1 and 1 of "
               "sigma_c (issue: post-peak stress above zero)",
        plot=plot, quick_note="unchanged"),
    ValidationCase(
        name="compression_localisation", case_file="ice_prism_compression.toml",
        quantity="broken fraction of the gauge length, dx = 1 cm", unit="-",
        measure=localisation, reference=lambda case: 0.25, relative=False, tolerance=0.25,
        source="failure localises (a crushing band or shear fault): at most half of the "
               "gauge length broken (issue: failure localises, no simultaneous pulverisation)",
        quick_note="unchanged"),
)
