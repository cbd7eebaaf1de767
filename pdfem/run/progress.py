"""Progress of a long run on the terminal: simulated time, steps per second, time left.

Quiet when asked, and when standard error is not a terminal (logs and CI stay clean).
"""

from __future__ import annotations

import sys
import time


class Progress:
    """Rate-limited one-line progress report on standard error.

    Parameters
    ----------
    end_time
        Simulated end time, s.
    enabled
        Force on/off; ``None`` means "when standard error is a terminal".
    interval
        Minimum wall-clock seconds between updates.
    start_time, start_step
        Simulated time (s) and step the run starts from (a restart: the checkpoint's); the rate
        and the time left are measured from there, not from t = 0.
    """

    def __init__(self, end_time: float, enabled: bool | None = None, interval: float = 0.5,
                 start_time: float = 0.0, start_step: int = 0):
        self.end_time = end_time
        self.start_time, self.start_step = float(start_time), int(start_step)
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.interval = interval
        self.t_start = time.perf_counter()
        self.t_last = -1e30
        self.steps = 0

    def update(self, sim_time: float, steps: int) -> None:
        """Report that ``steps`` steps have run and the simulation is at ``sim_time`` s."""
        self.steps = steps
        if not self.enabled:
            return
        now = time.perf_counter()
        if now - self.t_last < self.interval:
            return
        self.t_last = now
        wall = now - self.t_start
        frac = min(1.0, sim_time / self.end_time) if self.end_time > 0 else 1.0
        rate, eta = self.rate_and_eta(sim_time, steps, wall)
        sys.stderr.write(f"\r  t = {sim_time:.4e} s of {self.end_time:.4e} s ({100 * frac:5.1f} %)"
                         f"  {rate:8.1f} steps/s  ETA {eta:7.1f} s ")
        sys.stderr.flush()

    def rate_and_eta(self, sim_time: float, steps: int, wall: float) -> tuple[float, float]:
        """Steps per second and wall seconds left, from the steps and simulated time done since
        the start of this process (``start_step``, ``start_time``) in ``wall`` seconds."""
        done_steps = steps - self.start_step
        done = sim_time - self.start_time
        left = self.end_time - sim_time
        rate = done_steps / wall if wall > 0 else 0.0
        eta = wall * left / done if done > 0 else float("nan")
        return rate, max(eta, 0.0)

    def finish(self) -> float:
        """End the progress line; returns the wall-clock seconds since the start."""
        wall = time.perf_counter() - self.t_start
        if self.enabled:
            sys.stderr.write("\n")
            sys.stderr.flush()
        return wall
