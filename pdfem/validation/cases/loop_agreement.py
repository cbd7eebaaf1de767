"""The particle-pair loop against the full-family loop (``sphere_ice_loops.toml``).

The case runs twice, once per ``run.pd_loop``; the largest difference of the ice displacements
(every frame) and of the load on the sphere (every step), relative to their largest values, must
be round-off.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pdfem.case import Case
from pdfem.validation.case import Outcome, ValidationCase, replace_run, run_and_read

if TYPE_CHECKING:
    from matplotlib.figure import Figure

LOOPS = ("pairs", "full_family")


def run_loops(case: Case, directory: Path) -> dict:
    """Run ``case`` with each PD loop into ``directory/<loop>``: ``{loop: read_results dict}``."""
    return {loop: run_and_read(replace_run(case, pd_loop=loop), Path(directory) / loop) for loop in LOOPS}


def _series(r: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    h = r["histories"]["loads/sphere"]
    return r["ice"]["cube"]["u"], h["time"], h["force"][:, 2]


def difference(outcome: Outcome) -> float:
    """max(max|u_pairs - u_full| / max|u_pairs|, max|F_pairs - F_full| / max|F_pairs|)."""
    (ua, _, fa), (ub, _, fb) = (_series(outcome.data[loop]) for loop in LOOPS)
    if np.abs(fa).max() == 0.0:
        raise ValueError("the sphere never touched the ice")
    return float(max(np.abs(ua - ub).max() / np.abs(ua).max(), np.abs(fa - fb).max() / np.abs(fa).max()))


def quick(case: Case) -> Case:
    """Half the indentation time (0.5 ms)."""
    return replace_run(case, end_time=0.5 * case.run.end_time, output_interval=0.5 * case.run.output_interval)


def plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """Load on the sphere with both loops, and their difference."""
    ax, bx = fig.subplots(2, 1)
    (_, t, fa), (_, _, fb) = (_series(outcome.data[loop]) for loop in LOOPS)
    ax.plot(t * 1e3, -fa, lw=1.5, label="pairs")
    ax.plot(t * 1e3, -fb, "--", lw=1.0, label="full family")
    ax.set_ylabel("ice force on the sphere -F_z [N]")
    ax.legend()
    bx.plot(t * 1e3, np.abs(fa - fb), lw=0.9)
    bx.set_xlabel("time [ms]")
    bx.set_ylabel("|F_pairs - F_full| [N]")


CASES = (
    ValidationCase(
        name="pair_vs_full_family", case_file="sphere_ice_loops.toml",
        quantity="pairs vs full family", unit="-",
        measure=difference, reference=lambda case: 0.0, relative=False, tolerance=1e-9,
        execute=run_loops, quick=quick, plot=plot,
        source="identical sums in another order (Zhang et al. 2023, J. Mar. Sci. Eng. 11, 1154: "
               "particle-pair method vs the per-particle family loop): round-off only",
        quick_note="0.5 ms of indentation instead of 1 ms"),
)
