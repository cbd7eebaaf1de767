"""Fatigue plots of ``pdfem post --sn --plots DIR``: rainflow range histogram and the
cumulative exceedance of ranges against the S-N curve, one PNG per monitor (SI units: Pa).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from pdfem.post.fatigue import SNCurve


def exceedance(cycles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ranges (Pa, falling) and the number of cycles with a range at least as large.

    Parameters
    ----------
    cycles
        (n, 5) :func:`pdfem.post.fatigue.rainflow_cycles` (range, mean, count, start, end).
    """
    order = np.argsort(-cycles[:, 0], kind="stable")
    return cycles[order, 0], np.cumsum(cycles[order, 2])


def write_fatigue_plots(cycles: dict[str, np.ndarray], curve: SNCurve, stress: str,
                        directory: str | os.PathLike, bins: int = 10) -> list[Path]:
    """Write ``fatigue_<monitor>.png`` per monitor into ``directory`` (created if needed).

    Parameters
    ----------
    cycles
        {monitor: :func:`pdfem.post.fatigue.rainflow_cycles`} of the counted stress.
    curve
        The S-N curve, drawn over the exceedance.
    stress
        Name of the stress counted (for the titles).
    directory
        Where the PNG files go.
    bins
        Equal range bins of the histogram.

    Returns
    -------
    list of Path
        The files written (none for a monitor without cycles).
    """
    from matplotlib.figure import Figure  # no pyplot: no global figure state
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, c in cycles.items():
        if not c.size:
            continue
        fig = Figure(figsize=(8.0, 6.6), layout="constrained")
        top, bottom = fig.subplots(2, 1)
        top.hist(c[:, 0], bins=np.linspace(0.0, c[:, 0].max(), bins + 1), weights=c[:, 2],
                 edgecolor="k")
        top.set_title(f"Rainflow ranges of the {stress} stress at monitor '{name}'")
        top.set_xlabel("stress range [Pa]")
        top.set_ylabel("cycles (half cycles 0.5)")
        top.set_yscale("log")
        ranges, n = exceedance(c)
        bottom.step(n, ranges, where="post", label="cycles with a range at least this")
        ds = np.geomspace(max(ranges[-1], ranges[0] * 1e-3, 1.0), max(ranges[0], curve.stress),
                          200)
        bottom.plot(curve.endurance(ds), ds, "r", label="S-N curve: cycles to failure")
        bottom.set_xscale("log")
        bottom.set_yscale("log")
        bottom.set_xlabel("cycles")
        bottom.set_ylabel("stress range [Pa]")
        bottom.grid(alpha=0.3, which="both")
        bottom.legend(loc="best", fontsize="small")
        path = out / f"fatigue_{name}.png"
        fig.savefig(path, dpi=150, format="png")
        written.append(path)
    return written
