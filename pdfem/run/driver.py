"""Run a case: build its bodies, advance them together, write the results.

:func:`run_case` takes three named steps:

1. build (:func:`pdfem.run.build.build`): ice bodies, structures, contact pairs, particle
   forces and the coupler (:class:`pdfem.coupling.coupler.Coupler`), after the up-front
   estimates of particles, bonds and memory (:mod:`pdfem.run.preflight`; a run that cannot fit
   is refused before anything is allocated) and with the time-step check
   (:mod:`pdfem.run.timesteps`);
2. loop (:func:`pdfem.run.loop.run_loop`): coupling steps with the ice load on each structure,
   contact pairs and monitors every step, a frame every ``output_interval`` (fields, energies,
   structure reactions: :mod:`pdfem.run.outputs`), blow-up detection
   (:mod:`pdfem.run.blowup`; exit 3 with the results so far kept) and checkpoints
   (:mod:`pdfem.run.checkpoint`; a restart continues the results file in place); a stop
   signal (:mod:`pdfem.run.stop`) ends it early with a checkpoint and a last frame;
3. finish: close the files and report (:class:`RunSummary`).

The driver calls interfaces only (structures: :class:`pdfem.fem.base.Structure`; ice:
:class:`pdfem.pd.ice_interface.IceParticles`; particle forces:
:class:`pdfem.forces.base.ParticleForce`; output: :mod:`pdfem.output.source`), nothing of
numba or MPI.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path

from pdfem import __version__
from pdfem.case.schema import Case
from pdfem.output.files import inside
from pdfem.parallel.comm import world
from pdfem.run.blowup import BlowupMonitor
from pdfem.run.build import Setup, build
from pdfem.run.checkpoint import CHECKPOINT_NAME, read_checkpoint, restore
from pdfem.run.energy import EnergyBalance, budget_text
from pdfem.run.loop import LoopState, run_loop
from pdfem.run.outdir import OutDirLock, check_out_dir
from pdfem.run.outputs import Outputs, open_outputs, sources
from pdfem.run.preflight import preflight
from pdfem.run.profile import PROFILE_NAME, Profile, table
from pdfem.run.progress import Progress
from pdfem.run.stop import StopRequest


@dataclass
class RunSummary:
    """What a finished run reports (SI units)."""

    results: Path
    steps: int
    time_step: float
    end_time: float              # the simulated time reached (the case's end_time unless stopped)
    wall_seconds: float
    particles: int
    bonds: int
    broken_bonds: int
    frames: int
    energy: dict | None = None   # the energy row of the last frame (J), for the budget
    profile: list[dict] | None = None  # with profile=True: the time by component (s)
    stopped: str = ""            # the signal that stopped the run early ("SIGTERM"), or ""
    checkpoint: Path | None = None  # the checkpoint to restart from, when stopped

    def budget(self) -> str:
        """The energy budget at the end of the run (:func:`pdfem.run.energy.budget_text`)."""
        if not self.energy:
            return ""
        return f"  energy budget at t = {self.end_time:.4e} s (% of the work in):\n" + \
            budget_text(self.energy)

    def text(self) -> str:
        """A few lines for the terminal, the energy budget last."""
        return (f"pdfem: {'stopped by ' + self.stopped + ' after ' if self.stopped else ''}"
                f"{self.steps} steps of {self.time_step:.3e} s to t = {self.end_time:.4e} s "
                f"in {self.wall_seconds:.1f} s wall\n"
                f"  particles {self.particles:,}, bonds {self.bonds:,}, broken {self.broken_bonds:,}\n"
                f"  results: {self.results} ({self.frames} frames; open {self.results.with_suffix('.xdmf')} "
                "in ParaView)" + ("\n" + self.budget() if self.energy else "")
                + ("\n" + "\n".join(table(self.profile, self.particles))
                   if self.profile else ""))


def _start(case: Case, setup: Setup, outputs: Outputs, ckpt, say, comm) -> LoopState:
    """Initial forces, energy and first frame of a new run, or the state of a checkpoint."""
    if ckpt is None:
        setup.coupler.start()
        outputs.energy.start()
        outputs.frame(0.0)
        outputs.step(0.0)
        return LoopState(1, 1, case.run.output_interval, 0)
    restore(ckpt, setup.bodies, setup.structures, setup.coupler, comm)
    d = ckpt.driver
    outputs.resume(outputs.writer.path, d.frames, d.history_rows)
    outputs.energy.initial = d.initial_energy
    say(f"  restarting from {ckpt.path} at t = {d.time:.6e} s (step {d.step:,}), "
        f"appending to {outputs.writer.path}")
    return LoopState(d.step + 1, d.frames, d.next_output, d.broken)


def run_case(case: Case, out_dir: str | Path, *, quiet: bool = False, progress: bool | None = None,
             log=None, restart: str | Path | None = None, comm=None,
             profile: bool = False, stop: StopRequest | None = None) -> RunSummary:
    """Run a validated case and write ``results.h5`` (+ ``results.xdmf``) into ``out_dir``.

    Before building anything the particles, bonds and memory of the ice are estimated
    (:mod:`pdfem.run.estimates`) and a run that would not fit in the available memory is refused.
    Checkpoints (:mod:`pdfem.run.checkpoint`) go to ``out_dir/checkpoint.h5`` every
    ``run.checkpoint_interval_steps`` steps and every ``run.checkpoint_interval_minutes`` of
    wall time; blow-ups are detected by :class:`pdfem.run.blowup.BlowupMonitor`.

    Parameters
    ----------
    case
        The validated case (:func:`pdfem.case.schema.load_case`).
    out_dir
        Output directory (created; checked to be writable and locked for this run:
        :mod:`pdfem.run.outdir`).
    quiet
        No messages on standard output and no progress line.
    progress
        Force the progress line on/off (default: when standard error is a terminal).
    log
        Function taking one string (default: print to standard output).
    restart
        A checkpoint of this case to continue from; the run appends to ``out_dir/results.h5``
        (frames and history rows written after the checkpoint are dropped).
    comm
        The communicator (default :func:`pdfem.parallel.comm.world`).
    profile
        Time the run's components (:mod:`pdfem.run.profile`): the summary's ``profile`` and
        ``profile.json`` in ``out_dir``.
    stop
        A :class:`pdfem.run.stop.StopRequest` (set by the signal handlers of
        :func:`pdfem.run.stop.stop_signals`): once set on any rank, the run stops at the end of
        a coupling step with a checkpoint and a last frame, and the summary's ``stopped`` and
        ``checkpoint`` say so.

    Returns
    -------
    RunSummary

    Raises
    ------
    InputError
        Bad input (including a run too large for the memory, an unstable ``run.time_step``, a
        checkpoint of another case, an output directory that is a file, not writable or in use
        by another run).
    InstabilityError
        The run blew up; the results file holds every frame up to then (and one at the
        failure when the state is still finite).
    OutputError
        A results or checkpoint file could not be written (no space left, a file-size limit,
        an I/O error); the results file holds the frames written before.
    """
    comm = comm or world()
    out = check_out_dir(out_dir)
    with OutDirLock(out, enabled=comm.rank == 0):  # one run per output directory
        return _run(case, out, quiet, progress, log, restart, comm, profile, stop)


def _run(case: Case, out: Path, quiet: bool, progress: bool | None, log, restart, comm,
         profile: bool = False, stop: StopRequest | None = None) -> RunSummary:
    """:func:`run_case` in its checked and locked output directory ``out``."""
    quiet = quiet or comm.rank != 0  # one rank speaks for all
    say = (lambda s: None) if quiet else (log or (lambda s: print(s, flush=True)))
    ckpt = read_checkpoint(restart, case.text, case.file) if restart is not None else None
    report = preflight(case, comm)
    say(f"pdfem {__version__}: {case.file}{(' - ' + case.run.title) if case.run.title else ''}")
    for line in report:
        say(line)
    t_setup = time.perf_counter()
    # -- 1. build
    steps = None if ckpt is None else (ckpt.driver.time_step, ckpt.driver.ice_substeps,
                                       ckpt.driver.structure_substeps)
    setup = build(case, out, comm, say, steps)
    timing = Profile() if profile else None
    if timing is not None:
        timing.instrument(setup)
    meta = {"title": case.run.title, "ranks": comm.size, "time_step": setup.dt,
            "ice_substeps": setup.n_ice, "structure_substeps": setup.n_st,
            "pd_loop": case.run.pd_loop}
    writer, ice_writer = open_outputs(case, out, comm, meta, ckpt is not None, setup.particles)
    per_rank = ice_writer is not writer
    energy = EnergyBalance(setup.bodies, setup.structures, setup.forces, setup.coupler,
                           setup.dt / setup.n_ice)
    outputs = Outputs(writer, ice_writer, sources(setup, per_rank), energy)
    try:
        outputs.register(setup)
        monitor = BlowupMonitor(setup.bodies, setup.dt / setup.n_ice, setup.stable,
                                case.run.stability_check_interval_steps,
                                energy_tolerance=case.run.energy_tolerance)
        state = _start(case, setup, outputs, ckpt, say, comm)
    except BaseException:
        outputs.close()
        raise
    # -- 2. loop
    ckpt_path = inside(out, CHECKPOINT_NAME)
    every, minutes = case.run.checkpoint_interval_steps, case.run.checkpoint_interval_minutes
    if every or minutes:
        when = " and ".join(w for w in ((f"every {every:,} steps" if every else ""),
                                        (f"every {minutes:g} min" if minutes else "")) if w)
        say(f"  checkpoints {when} to {ckpt_path}")
    say(f"  set-up {time.perf_counter() - t_setup:.1f} s; running")
    bar = Progress(case.run.end_time, enabled=False if quiet else progress,
                   start_time=(state.first - 1) * setup.dt, start_step=state.first - 1)
    try:
        done = run_loop(case, setup, outputs, monitor, state, comm, bar, ckpt_path, say,
                        timing, stop)
    finally:  # -- 3. finish
        wall = bar.finish()
        outputs.close()
    rows = None
    if timing is not None:
        steps = done.step - state.first + 1
        rows = timing.rows(comm, setup.particles, steps, steps * setup.n_ice)
        if comm.rank == 0:
            (out / PROFILE_NAME).write_text(json.dumps(rows, indent=1))
    return RunSummary(writer.path, done.step, setup.dt, done.step * setup.dt, wall,
                      setup.particles, setup.bonds, setup.cut + done.broken, done.frames,
                      done.energy, rows, done.stopped, ckpt_path if done.stopped else None)
