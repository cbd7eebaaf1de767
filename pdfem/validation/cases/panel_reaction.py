"""Support reaction of a hull panel under a held uniform pressure (``panel_pressure_reaction.toml``):
the reaction at the clamped boundary at the end of the run against the resultant p A."""

from __future__ import annotations

from typing import TYPE_CHECKING

from pdfem.case import Case
from pdfem.validation.case import Outcome, ValidationCase, replace_run, replace_structure

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def measure(outcome: Outcome) -> float:
    """Vertical reaction (N) of the group ``fixed`` in the last frame."""
    return float(outcome.data["histories"]["structures/panel"]["reaction_fixed"][-1, 2])


def reference(case: Case) -> float:
    """p A: the pressure times the plating area length x breadth (N)."""
    s = case.structures[0]
    return s.loads[0].pressure * s.params["length"] * s.params["breadth"]


def quick(case: Case) -> Case:
    """Coarser tetrahedra (0.15 m) and 4 ms instead of 6 ms."""
    s = case.structures[0]
    return replace_run(replace_structure(case, params=dict(s.params, element_size=0.15)), end_time=4.0e-3)


def plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Reaction history against p A times the load's ramp."""
    h = outcome.data["histories"]["structures/panel"]
    pulse = outcome.case.structures[0].loads[0].pulse
    ax = fig.add_subplot()
    ax.plot(h["time"] * 1e3, h["reaction_fixed"][:, 2] / 1e3, "o-", ms=3, label="pdfem: reaction R_z")
    ax.plot(h["time"] * 1e3, [ref * pulse(t) / 1e3 for t in h["time"]], "k--", label="p A (load history)")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("force [kN]")
    ax.legend()


CASES = (
    ValidationCase(
        name="panel_reaction", case_file="panel_pressure_reaction.toml",
        quantity="panel support reaction", unit="N",
        measure=measure, reference=reference, plot=plot, quick=quick, tolerance=0.01,
        source="static equilibrium: the support reaction balances the pressure resultant, R = p A",
        quick_note="0.15 m tetrahedra instead of 0.1 m, 4 ms instead of 6 ms"),
)
