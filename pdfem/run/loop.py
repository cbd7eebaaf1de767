"""The coupled time loop of a run: coupling steps, output, blow-up checks, checkpoints.

:func:`run_loop` is the second of the driver's three steps (:mod:`pdfem.run.driver`). Every
coupling step it advances the coupler, writes the step's history rows and checks the motion for
a blow-up (:class:`pdfem.run.blowup.BlowupMonitor`), and every check interval and every frame
the energy balance (energy created stops the run); every ``output_interval`` it writes a frame; every ``checkpoint_interval_steps`` steps or
``checkpoint_interval_minutes`` of wall time it writes a checkpoint
(:func:`pdfem.run.checkpoint.write_checkpoint`). Under MPI it measures the load balance of the
split ice bodies every step and re-partitions them when due (:class:`pdfem.run.balance.LoadBalance`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pdfem.errors import InstabilityError
from pdfem.run.balance import LoadBalance
from pdfem.run.checkpoint import DriverState, write_checkpoint


@dataclass
class LoopState:
    """Where the loop stands (restored from a checkpoint on restart)."""

    first: int           # first step to take
    frames: int          # frames written
    next_output: float   # time of the next frame, s
    broken: int          # bonds broken in the run so far


@dataclass
class LoopResult:
    """What the loop did."""

    step: int
    frames: int
    broken: int
    energy: dict | None = None  # the energy row of the last frame (J)


def run_loop(case, setup, outputs, monitor, state: LoopState, comm, bar,
             ckpt_path: Path, say=lambda s: None) -> LoopResult:
    """Take the steps ``state.first`` .. ``setup.nsteps`` (see the module docstring); ``say``
    reports re-partitions.

    Raises
    ------
    InstabilityError
        The run blew up; a last frame at the failure is written when the state is still finite
        (serial runs), and the message says what the results file holds.
    """
    run, coupler, dt = case.run, setup.coupler, setup.dt
    every, minutes = run.checkpoint_interval_steps, run.checkpoint_interval_minutes
    frames, next_out, broken = state.frames, state.next_output, state.broken
    last_checkpoint = time.monotonic()
    step = state.first - 1
    t = step * dt
    last_frame = t
    energy = None
    balance = LoadBalance(case, setup, comm, say)
    try:
        for step in range(state.first, setup.nsteps + 1):
            t = step * dt
            try:
                broken += coupler.step()
            except FloatingPointError as exc:
                monitor.check_motion(t, step, force=True)
                raise InstabilityError(f"at t = {t:.6e} s (step {step:,}): {exc}") from None
            outputs.step(t)
            balance.after_step(step, t, outputs.writer)
            monitor.check_motion(t, step)
            frame = t >= next_out * (1 - 1e-9) or step == setup.nsteps
            if monitor.due(step) and not frame:  # the balance every check interval
                monitor.check_energy(t, step, outputs.energy.row())
            if frame:
                monitor.check_motion(t, step, force=True)
                e = outputs.frame(t)
                last_frame = t
                frames += 1
                while next_out <= t * (1 + 1e-9):
                    next_out += run.output_interval
                energy = e
                monitor.check_energy(t, step, e)
            due = bool(every) and step % every == 0
            if minutes and not due:  # rank 0's clock decides for all ranks
                due = comm.bcast(time.monotonic() - last_checkpoint >= 60 * minutes)
            if step < setup.nsteps and due:
                outputs.flush()
                write_checkpoint(ckpt_path, case.text,
                                 DriverState(step, t, dt, setup.n_ice, setup.n_st, next_out,
                                             frames, broken, outputs.energy.initial,
                                             outputs.writer.history_rows()),
                                 setup.bodies, setup.structures, coupler, comm)
                last_checkpoint = time.monotonic()
            bar.update(t, step)
    except InstabilityError as exc:
        note = ""
        if comm.size == 1 and t > last_frame and _finite_state(setup):
            try:
                outputs.frame(t)
                note = f", the last at the failure, t = {t:.6e} s"
            except Exception:  # the diagnosis matters more than this last frame
                note = ""
        outputs.close()
        raise InstabilityError(f"{exc}. The results so far are kept: {outputs.writer.path} "
                               f"({outputs.writer.n_frames} frames{note})") from None
    return LoopResult(step, frames, broken, energy)


def _finite_state(setup) -> bool:
    """Whether every ice position and velocity and every structure's state is finite."""
    return (all(np.isfinite(b.y).all() and np.isfinite(b.v).all() for b in setup.bodies)
            and all(s.is_finite() for s in setup.structures))
