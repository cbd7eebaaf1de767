"""The coupled time loop of a run: a coupling step, then the after-step tasks.

:func:`run_loop` is the second of the driver's three steps (:mod:`pdfem.run.driver`). Every
coupling step it advances the coupler, then runs the after-step tasks in order, each on its
own schedule:

1. :class:`Histories`: the step's history rows (every step, :meth:`pdfem.run.outputs.Outputs.step`);
2. the load balance of split ice bodies (:class:`pdfem.run.balance.LoadBalance`; under MPI);
3. :class:`MotionCheck`: runaway motion and NaN (:class:`pdfem.run.blowup.BlowupMonitor`, every
   check interval, and at every frame);
4. :class:`EnergyCheck`: energy created (every check interval between frames);
5. :class:`Frames`: a results frame every ``output_interval`` and at the last step, with its
   energy check;
6. :class:`Checkpoints`: every ``checkpoint_interval_steps`` steps or
   ``checkpoint_interval_minutes`` of wall time (:func:`pdfem.run.checkpoint.write_checkpoint`),
   and the stop on a signal (:mod:`pdfem.run.stop`): a checkpoint and a last frame at the step
   every rank agreed on, after which the loop ends;
7. :class:`ProgressTask`: the progress line.

A task is an object with ``after_step(s)`` taking the :class:`Step` just taken.
"""

from __future__ import annotations

import signal
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
    stopped: str = ""           # the signal that stopped the run ("SIGTERM"), "" if it ended


@dataclass
class Step:
    """The coupling step just taken: its number, end time (s), whether it is the last and
    whether a frame is due."""

    number: int
    t: float
    last: bool
    frame: bool


class Histories:
    """The history rows of every coupling step."""

    label = "histories"

    def __init__(self, outputs) -> None:
        self.outputs = outputs

    def after_step(self, s: Step) -> None:
        self.outputs.step(s.t)


class Balance:
    """The load balance of split ice bodies after every step (:mod:`pdfem.run.balance`)."""

    label = "load balance"

    def __init__(self, balance: LoadBalance, outputs) -> None:
        self.balance, self.outputs = balance, outputs

    def after_step(self, s: Step) -> None:
        self.balance.after_step(s.number, s.t, self.outputs.writer)


class MotionCheck:
    """Runaway motion and NaN, every check interval (the monitor's own schedule)."""

    label = "checks and progress"

    def __init__(self, monitor) -> None:
        self.monitor = monitor

    def after_step(self, s: Step) -> None:
        self.monitor.check_motion(s.t, s.number)


class EnergyCheck:
    """Energy created, every check interval between frames (a frame checks its own)."""

    label = "checks and progress"

    def __init__(self, monitor, outputs) -> None:
        self.monitor, self.outputs = monitor, outputs

    def after_step(self, s: Step) -> None:
        if self.monitor.due(s.number) and not s.frame:
            self.monitor.check_energy(s.t, s.number, self.outputs.energy.row())


class Frames:
    """A results frame every ``output_interval`` (s) and at the last step, each with the
    motion and energy checks."""

    label = "frames and checkpoints"

    def __init__(self, outputs, monitor, interval: float, state: LoopState, t0: float) -> None:
        self.outputs, self.monitor, self.interval = outputs, monitor, interval
        self.frames, self.next_output = state.frames, state.next_output
        self.last_time = t0          # s, time of the last frame written
        self.energy: dict | None = None

    def due(self, t: float, last: bool) -> bool:
        """Whether the step ending at ``t`` (s) writes a frame."""
        return t >= self.next_output * (1 - 1e-9) or last

    def after_step(self, s: Step) -> None:
        if not s.frame:
            return
        self.monitor.check_motion(s.t, s.number, force=True)
        e = self.outputs.frame(s.t)
        self.last_time = s.t
        self.frames += 1
        while self.next_output <= s.t * (1 + 1e-9):
            self.next_output += self.interval
        self.energy = e
        self.monitor.check_energy(s.t, s.number, e)

    def at_stop(self, s: Step) -> None:
        """The last frame of a run stopped at step ``s`` (unless one was written there); the
        schedule is not advanced (a restart drops this frame: the checkpoint counts the frames
        before it)."""
        if s.frame:
            return
        self.monitor.check_motion(s.t, s.number, force=True)
        self.energy = self.outputs.frame(s.t)
        self.last_time = s.t
        self.frames += 1


class Checkpoints:
    """A checkpoint every ``every`` steps and every ``minutes`` of wall time, never at the last
    step; and the stop on a signal.

    After every step one small max-reduction over the ranks (two integers) gives every rank
    the same answers: whether a rank's clock says a checkpoint is due, and the stop signal a
    rank received (``stop``, a :class:`pdfem.run.stop.StopRequest`), so a signal on any rank
    stops every rank at the same step. A stopped run writes its checkpoint, then a last frame
    (:meth:`Frames.at_stop`), and :attr:`stopped` names the signal.
    """

    label = "frames and checkpoints"

    def __init__(self, case, setup, outputs, frames: Frames, path: Path, comm,
                 broken, stop=None, say=lambda s: None) -> None:
        run = case.run
        self.every, self.minutes = run.checkpoint_interval_steps, run.checkpoint_interval_minutes
        self.case, self.setup, self.outputs, self.frames = case, setup, outputs, frames
        self.path, self.comm, self.broken, self.stop, self.say = path, comm, broken, stop, say
        self.last = time.monotonic()
        self.stopped = ""

    def after_step(self, s: Step) -> None:
        due = bool(self.every) and s.number % self.every == 0
        clock = bool(self.minutes) and time.monotonic() - self.last >= 60 * self.minutes
        clock, sig = self.comm.allreduce_max(
            np.array([clock, self.stop.signal if self.stop else 0], dtype=np.int64))
        due = due or bool(clock)
        if s.last:
            return
        if sig:
            self.stopped = signal.Signals(int(sig)).name
            self.say(f"  {self.stopped}: stopping at t = {s.t:.6e} s (step {s.number:,}) with a "
                     "checkpoint and a last frame (a second Ctrl-C stops at once)")
            self.write(s)
            self.frames.at_stop(s)
        elif due:
            self.write(s)

    def write(self, s: Step) -> None:
        """Write the checkpoint at the end of step ``s``."""
        st, out = self.setup, self.outputs
        out.flush()
        write_checkpoint(self.path, self.case.text,
                         DriverState(s.number, s.t, st.dt, st.n_ice, st.n_st,
                                     self.frames.next_output, self.frames.frames, self.broken(),
                                     out.energy.initial, out.writer.history_rows()),
                         st.bodies, st.structures, st.coupler, self.comm)
        self.last = time.monotonic()


class ProgressTask:
    """The progress line after every step."""

    label = "checks and progress"

    def __init__(self, bar) -> None:
        self.bar = bar

    def after_step(self, s: Step) -> None:
        self.bar.update(s.t, s.number)


def run_loop(case, setup, outputs, monitor, state: LoopState, comm, bar,
             ckpt_path: Path, say=lambda s: None, profile=None, stop=None) -> LoopResult:
    """Take the steps ``state.first`` .. ``setup.nsteps`` (see the module docstring); ``say``
    reports re-partitions; ``profile`` (a :class:`pdfem.run.profile.Profile`, with the
    coupling step's parts wrapped) also times the tasks and the loop; ``stop`` (a
    :class:`pdfem.run.stop.StopRequest`) ends the loop early, with a checkpoint, once a stop
    signal reached any rank.

    Raises
    ------
    InstabilityError
        The run blew up; a last frame at the failure is written when every process meets the
        failure at the same point and the state is still finite, and the message says what
        the results file holds.
    """
    coupler, dt = setup.coupler, setup.dt
    broken = state.broken
    step = state.first - 1
    t = step * dt
    frames = Frames(outputs, monitor, case.run.output_interval, state, t)
    checkpoints = Checkpoints(case, setup, outputs, frames, ckpt_path, comm, lambda: broken,
                              stop, say)
    tasks = [Histories(outputs), Balance(LoadBalance(case, setup, comm, say), outputs),
             MotionCheck(monitor), EnergyCheck(monitor, outputs), frames, checkpoints,
             ProgressTask(bar)]
    if profile is not None:
        profile.start_loop(tasks)
    try:
        for step in range(state.first, setup.nsteps + 1):
            t = step * dt
            try:
                broken += coupler.step()
            except FloatingPointError as exc:
                monitor.check_motion(t, step, force=True)
                raise InstabilityError(f"at t = {t:.6e} s (step {step:,}): {exc}") from None
            last = step == setup.nsteps
            s = Step(step, t, last, frames.due(t, last))
            for task in tasks:
                task.after_step(s)
            if checkpoints.stopped:
                break
    except InstabilityError as exc:
        note = ""
        if comm.failures_shared and t > frames.last_time and _finite_state(setup):
            try:
                outputs.frame(t)
                note = f", the last at the failure, t = {t:.6e} s"
            except Exception:  # the diagnosis matters more than this last frame
                note = ""
        outputs.close()
        raise InstabilityError(f"{exc}. The results so far are kept: {outputs.writer.path} "
                               f"({outputs.writer.n_frames} frames{note})") from None
    if profile is not None:
        profile.stop_loop()
    return LoopResult(step, frames.frames, broken, frames.energy, checkpoints.stopped)


def _finite_state(setup) -> bool:
    """Whether every ice position and velocity and every structure's state is finite."""
    return (all(np.isfinite(b.y).all() and np.isfinite(b.v).all() for b in setup.bodies)
            and all(s.is_finite() for s in setup.structures))
