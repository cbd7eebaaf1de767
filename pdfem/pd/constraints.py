"""Prescribed particle velocities of an ice body (drivers, supports that move)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class VelocityConstraint:
    """Particles ``index`` move with ``velocity`` (m/s) scaled by min(1, t / ramp_time)."""

    index: np.ndarray
    velocity: np.ndarray
    ramp_time: float = 0.0

    def value(self, t: float) -> np.ndarray:
        """The prescribed velocity (m/s) at time ``t`` (s)."""
        s = 1.0 if self.ramp_time <= 0.0 else min(1.0, max(t, 0.0) / self.ramp_time)
        return self.velocity * s

    def acceleration(self, t: float) -> np.ndarray:
        """The prescribed acceleration (m/s^2) at time ``t`` (s)."""
        if self.ramp_time > 0.0 and t < self.ramp_time:
            return self.velocity / self.ramp_time
        return np.zeros(3)
