"""Where a run's time goes: ``pdfem run CASE --profile``.

A :class:`Profile` wraps the methods of the built objects that do each part of a coupling step
and adds up the wall time spent in them, by component:

- ``bonds and failure``: the ice bodies' bond forces, dilatation and breaking
  (``compute_forces``, ``refresh_forces``);
- one row per particle force, named by its ``label`` (``short-range contact``, ``water``,
  ``gravity``);
- ``surface contact``: detection and resolution of the particles against the structures'
  contact surfaces (``SurfaceContact.resolve``); ``contact surfaces``: their update to the
  structures' new positions (``set_surface``) and the part of each surface near the ice made
  ready (``near_surface``: the near facets, their grid and pseudo-normals);
- ``structures``: the structures' own steps and their surface motion (the surface motion's
  ``over``, ``after``, ``begin``, ``sample``, ``respond``, ``drive_work``);
- ``coupling (rest)``: what the coupling step does besides (the ice's integration, the hand-over
  of impulses, the step's Python);
- one row per after-step task of the loop (its ``label``: histories, frames and checkpoints,
  checks and progress);
- ``loop (rest)``: the loop's own remainder.

The time of a call is booked to its own component only: a wrapped call inside another wrapped
call is taken out of the outer one's time, so the rows add up to the loop's wall time. The
table gives each row in seconds (the largest over the ranks), as a share of the loop, per
coupling step and per particle-step (the ice's particles times its steps, from all ranks). SI
units (s).
"""

from __future__ import annotations

import time
from typing import Any

PROFILE_NAME = "profile.json"
"""The profile's file in the output directory: the rows of :meth:`Profile.rows` as JSON."""

MOTION_METHODS = ("over", "after", "begin", "sample", "respond", "drive_work")
"""The surface motion's methods (:class:`pdfem.fem.surface_motion.SurfaceMotion`): the
structures' share of a coupling step."""


class Profile:
    """Wall time by component (s), exclusive of the wrapped calls made inside."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}
        self._stack: list[list[float]] = []   # per open call: [start, time in wrapped calls]
        self.loop = 0.0                        # s, the loop's wall time
        self._loop_start = 0.0

    def wrap(self, obj: Any, method: str, label: str) -> None:
        """Replace ``obj.method`` (on this instance) by a call that books its time to ``label``."""
        inner = getattr(obj, method)
        self.seconds.setdefault(label, 0.0)
        seconds, stack = self.seconds, self._stack

        def timed(*args, **kwargs):
            stack.append([time.perf_counter(), 0.0])
            try:
                return inner(*args, **kwargs)
            finally:
                start, nested = stack.pop()
                spent = time.perf_counter() - start
                seconds[label] += spent - nested
                if stack:
                    stack[-1][1] += spent

        setattr(obj, method, timed)

    def instrument(self, setup) -> None:
        """Wrap the coupling step's parts of a built run (:class:`pdfem.run.build.Setup`)."""
        for body in setup.bodies:
            self.wrap(body, "compute_forces", "bonds and failure")
            self.wrap(body, "refresh_forces", "bonds and failure")
        for force in setup.forces:
            self.wrap(force, "add_forces", force.label)
        for pair in setup.coupler.pairs:
            self.wrap(pair.contact, "resolve", "surface contact")
            self.wrap(pair.contact, "set_surface", "contact surfaces")
            self.wrap(pair.contact, "near_surface", "contact surfaces")
        for record in setup.coupler.records:
            for method in MOTION_METHODS:
                self.wrap(record.motion, method, "structures")
        self.wrap(setup.coupler, "step", "coupling (rest)")

    def start_loop(self, tasks: list) -> None:
        """Wrap the loop's after-step tasks, each booked to its ``label``, and start counting
        (the set-up's first forces and frame are not the loop's)."""
        for task in tasks:
            self.wrap(task, "after_step", task.label)
        for label in self.seconds:
            self.seconds[label] = 0.0
        self._loop_start = time.perf_counter()

    def stop_loop(self) -> None:
        """The loop ended: its wall time so far is :attr:`loop`."""
        self.loop += time.perf_counter() - self._loop_start

    def rows(self, comm, particles: int, steps: int, ice_steps: int) -> list[dict]:
        """The table's rows (every rank calls; the seconds are the largest over the ranks):
        component, seconds, share of the loop, s per coupling step, s per particle-step
        (``None`` without ice); the last row, ``total``, also gives the coupling ``steps``."""
        mine = dict(self.seconds, **{"loop (rest)": self.loop - sum(self.seconds.values()),
                                     "total": self.loop})
        parts = comm.allgather(mine)
        loop = max(p["total"] for p in parts)
        particle_steps = particles * ice_steps
        out = []
        for label in mine:
            s = max(p[label] for p in parts)
            out.append({"component": label, "seconds": s,
                        "share": s / loop if loop > 0 else 0.0,
                        "per_step": s / max(steps, 1),
                        "per_particle_step": s / particle_steps if particle_steps > 0 else None})
        out[-1]["steps"] = steps
        return out


def table(rows: list[dict], particles: int) -> list[str]:
    """The profile as text lines: one row per component, the largest first, the total last."""
    lines = [f"  profile: {rows[-1]['steps']:,} coupling steps, {particles:,} ice particles",
             f"    {'component':<26}{'s':>10}{'%':>7}{'ms/step':>10}{'ns/particle-step':>18}"]
    body = sorted(rows[:-1], key=lambda r: -r["seconds"]) + rows[-1:]
    for r in body:
        pps = r["per_particle_step"]
        lines.append(f"    {r['component']:<26}{r['seconds']:>10.3f}{100 * r['share']:>7.1f}"
                     f"{1e3 * r['per_step']:>10.3f}"
                     + (f"{1e9 * pps:>18.1f}" if pps is not None else f"{'-':>18}"))
    return lines
