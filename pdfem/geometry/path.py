"""A prescribed displacement path: piecewise-linear displacement (m) of time (s).

Given points ``[[t0, ux, uy, uz], [t1, ...], ...]`` with t strictly increasing and t0 >= 0, the
displacement is interpolated linearly between points, equals the first point's before ``t0`` and
holds the last point's after the last time. The velocity is the slope of the segment holding
``t`` (right-continuous: at a point's time it is the slope of the segment that starts there;
zero before the first and from the last point on). Used by ice regions
(:mod:`pdfem.pd.constraints`) and rigid bodies (:mod:`pdfem.motion.rigid`). Units: s, m, m/s.
"""

from __future__ import annotations

import numpy as np


class DisplacementPath:
    """A piecewise-linear displacement path.

    Parameters
    ----------
    points
        (K, 4) rows ``[t, ux, uy, uz]`` (s, m), K >= 1, t strictly increasing, first t >= 0.

    Raises
    ------
    ValueError
        If the rows are not four finite numbers, the times do not increase strictly, or the
        first time is negative.
    """

    def __init__(self, points) -> None:
        p = np.asarray(points, dtype=np.float64)
        if p.ndim != 2 or p.shape[0] < 1 or p.shape[1] != 4 or not np.all(np.isfinite(p)):
            raise ValueError("a path is a list of rows [t, ux, uy, uz] of finite numbers (s, m)")
        if p[0, 0] < 0.0:
            raise ValueError(f"the path's first time must be >= 0 s (got {p[0, 0]:g})")
        if np.any(np.diff(p[:, 0]) <= 0.0):
            raise ValueError("the path's times must increase strictly from row to row")
        self.times = np.ascontiguousarray(p[:, 0])
        self.values = np.ascontiguousarray(p[:, 1:])

    def displacement(self, t: float) -> np.ndarray:
        """(3,) displacement (m) at time ``t`` (s)."""
        return np.array([np.interp(t, self.times, self.values[:, k]) for k in range(3)])

    def velocity(self, t: float) -> np.ndarray:
        """(3,) velocity (m/s) at time ``t`` (s): the slope of the segment that holds ``t``."""
        k = int(np.searchsorted(self.times, t, side="right"))  # times[k-1] <= t < times[k]
        if k == 0 or k == len(self.times):
            return np.zeros(3)
        return (self.values[k] - self.values[k - 1]) / (self.times[k] - self.times[k - 1])

    def mean_velocity(self, t0: float, t1: float) -> np.ndarray:
        """(3,) mean velocity (m/s) over ``[t0, t1]`` (s): the displacement increment over the
        interval divided by its length, so that a drift with it lands on the path exactly."""
        if t1 <= t0:
            return self.velocity(t0)
        return (self.displacement(t1) - self.displacement(t0)) / (t1 - t0)
