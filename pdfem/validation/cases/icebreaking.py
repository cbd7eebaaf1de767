"""Icebreaking (``icebreaker_tiny.toml``): a towed hull breaking floating level ice.

Two quantities of one run of a rigid hull towed through a floating ice sheet (docs/icebreaking.md):

- ``icebreaking_resistance``: the mean ice resistance (N, the hull's ice load against its
  heading, averaged over the steady phase by :func:`pdfem.post.resistance.steady_figures`)
  against Lindqvist's (1989) level-ice resistance of the same hull in the same ice *at zero
  speed*, R_c + R_b + R_s (crushing at the stem, bending, submersion of the broken pieces;
  :func:`pdfem.post.lindqvist.lindqvist_resistance`). Lindqvist's speed factors,
  (1 + 1.4 v / sqrt(g h)) on R_c + R_b and (1 + 9.4 v / sqrt(g L)) on R_s, stand for the
  inertia of the water and the broken ice that still water without flow lacks (docs/water.md),
  so the speed-free part is the formula this model can be held to; :func:`lindqvist_figures`
  gives both, and the report records the ratio to each. The tolerance, 50 %, is that of a
  regression on full-scale Baltic trials (its authors quote about 20 % on their own ships)
  applied to model ice broken by a two-layer lattice.
- ``icebreaking_pieces_under_hull``: the share of the channel's ice pushed under the water
  by the bow: of the particles that started in the hull's path (|y| < B/2 at the sheet, from
  the sheet's near edge to where the stem is at the end less the bow's entrance length), the
  fraction that ends more than one ice thickness below the sheet's bottom. An icebreaking bow
  bends the sheet down and the broken pieces turn and slide down along the hull (Lindqvist's
  R_s is the cost of holding them there); a hull that merely pushed the ice ahead or let it pass
  through would leave the fraction near 0. Reference 1 (every piece of the channel under
  water), absolute tolerance 0.35: pieces near the water line at the shoulders and ones that
  have floated up astern of the stem count as not submerged.

Units: SI.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from pdfem.case import Case
from pdfem.models.icebreaker import PARAMETERS
from pdfem.post.lindqvist import lindqvist_resistance
from pdfem.post.resistance import resistance_history, steady_figures
from pdfem.validation.case import Outcome, ValidationCase, replace_run

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def _hull(case: Case) -> dict:
    """The hull's parameters (the model's defaults filled in), m and rad."""
    params = {k: v[0] for k, v in PARAMETERS.items()}
    return params | dict(case.structures[0].params)


def _path(case: Case) -> np.ndarray:
    """The hull's towing path rows (t, dx, dy, dz): s and m."""
    return np.asarray(case.structures[0].path, dtype=np.float64)


def _speed(case: Case) -> float:
    """The towing speed (m/s): the slope of the path's last segment."""
    p = _path(case)
    return float((p[-1, 1] - p[-2, 1]) / (p[-1, 0] - p[-2, 0]))


def _thickness(case: Case) -> float:
    box = case.ice[0].shape
    return float(box.max[2] - box.min[2])


def lindqvist_figures(case: Case) -> dict[str, float]:
    """Lindqvist's (1989) resistance of the case's hull and ice (N; :func:`lindqvist_resistance`
    plus ``static`` = R_c + R_b + R_s, the part without the speed factors)."""
    hull, ice = _hull(case), case.ice[0].material
    r = lindqvist_resistance(
        length=hull["length"], beam=hull["beam"], draught=hull["draught"],
        stem_angle=hull["stem_angle"], entrance_angle=hull["entrance_angle"],
        thickness=_thickness(case), bending_strength=ice.tensile_strength,
        youngs_modulus=ice.youngs_modulus, speed=_speed(case), friction=case.contacts[0].friction,
        poisson_ratio=ice.poisson_ratio, water_density=case.water.density,
        ice_density=ice.density)
    return r | {"static": r["crushing"] + r["bending"] + r["submersion"]}


def mean_resistance(outcome: Outcome) -> float:
    """The steady-phase mean of the hull's ice resistance (N)."""
    h = outcome.data["histories"]["loads/" + outcome.case.structures[0].name]
    return float(steady_figures(h["time"], resistance_history(h["force"]))["mean"])


def resistance_reference(case: Case) -> float:
    """Lindqvist's R_c + R_b + R_s (N) for the case."""
    return lindqvist_figures(case)["static"]


def _channel(outcome: Outcome) -> tuple[np.ndarray, np.ndarray]:
    """The reference positions (m) of the channel's particles and their final heights (m)."""
    case = outcome.case
    hull = _hull(case)
    body = outcome.data["ice"][case.ice[0].name]
    x0, z = body["x0"], body["x0"][:, 2] + body["u"][-1, :, 2]
    entrance = 0.5 * hull["beam"] / math.tan(hull["entrance_angle"])
    t_end = float(outcome.data["time"][-1])
    stem = 0.5 * hull["length"] + float(np.interp(t_end, _path(case)[:, 0], _path(case)[:, 1]))
    near = float(case.ice[0].shape.min[0])
    inside = ((np.abs(x0[:, 1]) < 0.5 * hull["beam"]) & (x0[:, 0] >= near)
              & (x0[:, 0] <= stem - entrance))
    return x0[inside], z[inside]


def submerged_fraction(outcome: Outcome) -> float:
    """Fraction of the channel's particles more than one ice thickness below the sheet's
    bottom at the end of the run."""
    x0, z = _channel(outcome)
    if len(z) == 0:
        raise ValueError("no particle of the sheet lies in the hull's path up to its shoulders "
                         "at the end of the run: run longer")
    bottom = float(outcome.case.ice[0].shape.min[2])
    return float(np.mean(z < bottom - _thickness(outcome.case)))


def quick(case: Case) -> Case:
    """The case run to 0.9 s (the bow fully in the ice at 0.77 s; a shorter steady phase)."""
    return replace_run(case, end_time=min(case.run.end_time, 0.9))


def plot_resistance(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """The resistance history, its steady mean and Lindqvist's figures."""
    h = outcome.data["histories"]["loads/" + outcome.case.structures[0].name]
    r = resistance_history(h["force"])
    f = steady_figures(h["time"], r)
    lq = lindqvist_figures(outcome.case)
    ax = fig.add_subplot()
    ax.plot(h["time"], r, lw=0.6, label="pdfem: ice resistance")
    ax.hlines(value, f["start"], f["end"], colors="C1", label=f"steady mean {value:.3g} N")
    ax.axhline(ref, color="k", ls="--", label=f"Lindqvist at zero speed {ref:.3g} N")
    ax.axhline(lq["total"], color="0.5", ls=":", label=f"Lindqvist at the speed {lq['total']:.3g} N")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("resistance [N]")
    ax.legend(fontsize="small")


def plot_pieces(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Final height of the channel's particles along the hull's path."""
    x0, z = _channel(outcome)
    bottom = float(outcome.case.ice[0].shape.min[2])
    ax = fig.add_subplot()
    ax.plot(x0[:, 0], z, ".", ms=2, label="channel particles at the end")
    ax.axhline(bottom - _thickness(outcome.case), color="k", ls="--",
               label="one thickness below the sheet's bottom")
    ax.set_xlabel("x at the start [m]")
    ax.set_ylabel("z at the end [m]")
    ax.set_title(f"{100 * value:.0f} % of the channel's ice under water")
    ax.legend(fontsize="small")


_QUICK = "run to 0.9 s instead of 1.2 s (steady phase from 0.67 s: about one breaking cycle)"

CASES = (
    ValidationCase(
        name="icebreaking_resistance", case_file="icebreaker_tiny.toml",
        quantity="mean level-ice resistance of a towed icebreaker hull", unit="N",
        measure=mean_resistance, reference=resistance_reference, plot=plot_resistance,
        quick=quick, tolerance=0.5,
        source="Lindqvist, G. (1989), A straightforward method for calculation of ice "
               "resistance of ships, POAC'89, vol. 2, 722-735: R_c + R_b + R_s (without the "
               "speed factors, which stand for the water's inertia that still water lacks)",
        quick_note=_QUICK),
    ValidationCase(
        name="icebreaking_pieces_under_hull", case_file="icebreaker_tiny.toml",
        quantity="share of the channel's broken ice pushed under water along the hull",
        unit="-", measure=submerged_fraction, reference=lambda case: 1.0, plot=plot_pieces,
        quick=quick, tolerance=0.35, relative=False,
        source="the bending mode of icebreaking: the bow bends the sheet down and the broken "
               "pieces turn and slide under along the hull (Lindqvist 1989, R_s; Enkvist 1972)",
        quick_note=_QUICK),
)
