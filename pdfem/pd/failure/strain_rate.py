"""The strain rate each ice particle sees, for a failure law whose strength depends on it.

The rate is taken from the particle's dilatation over the last step: eps_rate =
|theta_n - theta_(n-1)| / (dt (1 - 2 nu)), the axial strain rate of a uniaxial stress state with
that volumetric rate (exact there; in a confined, volume-preserving flow it underestimates the
rate, and the strength then leans to its ductile value). It lags by one step, as every quantity
that a step's force pass uses from the state before it. SI units: 1/s.
"""

from __future__ import annotations

import numpy as np


class RateTracker:
    """Per-particle strain rates of an ice body and the strength factors a law gives them.

    Parameters
    ----------
    law
        The failure law (:meth:`~pdfem.pd.failure.ice.IceFailure.strength_factor`).
    poisson_ratio
        nu of the ice (-).
    """

    def __init__(self, law, poisson_ratio: float) -> None:
        self.law = law
        self.scale = 1.0 / (1.0 - 2.0 * poisson_ratio)
        self.theta: np.ndarray | None = None  # the dilatation at the last step's start
        self.factors: np.ndarray | None = None  # (N,) strength factors; None: 1 everywhere

    def advance(self, theta: np.ndarray, dt: float) -> None:
        """At a step's start: the rate since the last step's start from ``theta`` (the
        dilatation now) and the step ``dt`` (s), and the strength factors for the step."""
        if self.theta is not None and dt > 0.0:
            rate = np.abs(theta - self.theta) * (self.scale / dt)
            self.factors = self.law.strength_factor(rate)
        self.theta = theta.copy()
