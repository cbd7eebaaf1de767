"""An ice bar striking a rigid wall end-on (``bar_rigid_wall.toml``), and an elastic steel wall
advanced by implicit Newmark steps (``bar_elastic_wall_implicit.toml``, whose give changes the
references by about 0.1 %): contact duration 2L/c and contact force rho c A v of 1-D elastic
impact theory, from the wall's load history."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pdfem.case import Case
from pdfem.run.build_ice import ice_material
from pdfem.validation.case import Outcome, ValidationCase
from pdfem.validation.measure import contact_window

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _force(outcome: Outcome) -> tuple[np.ndarray, np.ndarray, float]:
    """Times (s) and force pressing on the wall (N, positive) at every step; the step (s)."""
    h = outcome.data["histories"]["loads/wall"]
    return h["time"], -h["force"][:, 2], float(outcome.data["meta"]["time_step"])


def _bar(case: Case) -> tuple[float, float, float, float]:
    """Length (m), section area (m^2), speed (m/s) and wave speed (m/s) of the bar."""
    ice = case.ice[0]
    lo, hi = ice.shape.min, ice.shape.max
    return (hi[2] - lo[2], (hi[0] - lo[0]) * (hi[1] - lo[1]), abs(ice.initial_velocity[2]),
            ice_material(ice.material).wave_speed)


def duration(outcome: Outcome) -> float:
    """Number of steps with a nonzero contact force times the step (s)."""
    _, f, dt = _force(outcome)
    first, last = contact_window(f)
    return (last - first + 1) * dt


def plateau(outcome: Outcome) -> float:
    """Mean contact force (N) during the contact, the first-touch steps and the last left out."""
    _, f, _ = _force(outcome)
    first, last = contact_window(f)
    return float(f[first + 2:last - 1].mean())


def plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """The wall force history against the rectangular pulse of 1-D impact theory."""
    t, f, _ = _force(outcome)
    length, area, v, c = _bar(outcome.case)
    first, _ = contact_window(f)
    t0 = t[first]
    ax = fig.add_subplot()
    ax.plot(t * 1e3, f / 1e3, lw=0.9, label="pdfem")
    ax.plot(np.array([t[0], t0, t0, t0 + 2 * length / c, t0 + 2 * length / c, t[-1]]) * 1e3,
            np.array([0, 0, 1, 1, 0, 0]) * outcome.case.ice[0].material.density * c * area * v / 1e3,
            "k--", label="1-D theory: rho c A v for 2L/c")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("force on the wall [kN]")
    ax.legend()


_JOHNSON = "1-D elastic impact of a bar on a rigid wall (Johnson, Impact Strength of Materials, 1972, ch. 1)"


def _entries(suffix: str, case_file: str, note: str) -> tuple[ValidationCase, ValidationCase]:
    """The duration and force entries of ``case_file``, named ``wall_contact_*<suffix>``."""
    common = dict(case_file=case_file, plot=plot, tolerance=0.05,
                  quick_note="unchanged (960 particles, 0.45 ms)")
    return (
        ValidationCase(
            name=f"wall_contact_duration{suffix}", quantity="wall contact duration", unit="s",
            measure=duration, reference=lambda case: 2 * _bar(case)[0] / _bar(case)[3],
            source=f"{_JOHNSON}: t = 2L/c, c = sqrt(E/rho){note}", **common),
        ValidationCase(
            name=f"wall_contact_force{suffix}", quantity="wall contact force", unit="N",
            measure=plateau,
            reference=lambda case: (case.ice[0].material.density * _bar(case)[3]
                                    * _bar(case)[1] * _bar(case)[2]),
            source=f"{_JOHNSON}: F = rho c A v{note}", **common),
    )


CASES = (_entries("", "bar_rigid_wall.toml", "")
         + _entries("_implicit", "bar_elastic_wall_implicit.toml",
                    "; the wall an elastic steel slab advanced by implicit Newmark steps, whose "
                    "give (static stiffness ~5e9 N/m under the bar's end, Johnson, Contact "
                    "Mechanics, 1985, Sec. 3.8) moves the reference by about 0.1 %"))
