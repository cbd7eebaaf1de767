"""The milling case's ice torque read as per-step peaks and as running means, for runs side by
side (explicit against implicit blades, or one step against half of it).

For each results directory: the per-coupling-step ice torque about the shaft
(:func:`pdfem.validation.cases.milling.shaft_torque`: ``Q = -n . (M - c x F)``), its largest
value, the largest value of its running means over 0.1, 0.2, 0.5 and 1 ms (boxcar windows of the
nearest whole number of coupling steps), and its integral after the spin-up ramp (the ice's
angular impulse, N m s; the ramp is the case's ``ramp_time``, or ``--ramp`` (s) for runs of an
earlier version of the case: 0.01 for those before 2026-11-29 15:40 UTC). The per-step peak depends on the scheme and on the step; the running
means over 0.1 ms or more are the figures to compare (docs/structures_time_integration.md).

Run::

    python benchmarks/milling_running_means.py DIR [DIR ...] [--case CASE] [--ramp S]

SI units: N m, N m s, s.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from pdfem.case.schema import load_case
from pdfem.output import read_results
from pdfem.validation.cases import milling

WINDOWS = (1e-4, 2e-4, 5e-4, 1e-3)   # s


def running_peaks(t: np.ndarray, q: np.ndarray) -> dict[float, float]:
    """Largest running mean of ``q`` over each of :data:`WINDOWS` (s)."""
    dt = float(np.diff(t).mean())
    out = {}
    for w in WINDOWS:
        n = max(1, int(round(w / dt)))
        out[w] = float(np.convolve(q, np.ones(n) / n, mode="valid").max())
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path, help="output directories of 'pdfem run'")
    ap.add_argument("--case", type=Path, default=Path(__file__).parents[1] / "models"
                    / "propeller_ice_milling.toml")
    ap.add_argument("--ramp", type=float, default=None,
                    help="spin-up time left out (s); default: the case's ramp_time")
    args = ap.parse_args()
    case = load_case(args.case)
    ramp = case.structures[0].ramp_time if args.ramp is None else args.ramp
    for d in args.runs:
        t, q = milling.shaft_torque(case, read_results(d / "results.h5"))
        dt = float(np.diff(t).mean())
        means = ", ".join(f"{w * 1e3:g} ms {v / 1e3:.2f}" for w, v in running_peaks(t, q).items())
        print(f"{d}: per step {q.max() / 1e3:.1f}, {means} kN m; angular impulse after the "
              f"ramp {np.sum(q[t > ramp]) * dt:.1f} N m s")


if __name__ == "__main__":
    main()
