"""The ``[run]`` section of a case file: time loop, output, checkpoints and stability checks."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, model_validator

from pdfem.case.fields import (Boolean, Choice, Number, Positive, Section, Text, Vec3, Vector, Whole,
                               fail)

MAX_FRAMES = 10**6
"""Most result frames a run may write (end_time / output_interval): each frame holds every ice
particle's fields, so a million frames of a body of ten thousand particles are about 100 GB."""

#: The peridynamic force loops.
PdLoop = Choice("pairs", "full_family")


class RunSection(Section):
    """Time-loop settings (seconds)."""

    end_time: Annotated[float, Positive("s")] = Field(
        description="Simulated time at which the run ends (s). Required.")
    output_interval: Annotated[float, Positive("s")] | None = Field(
        None, description="Simulated time between result frames (s), at most end_time and at "
                          "least end_time / 1e6 (a million frames). Default: end_time / 20.")
    time_step: Annotated[float, Number("s", ge=0.0)] = Field(
        0.0, description="Fixed coupling time step (s); 0 = automatic (the Silling & Askari stable "
                         "estimate times safety_factor). Default: 0 (automatic).")
    safety_factor: Annotated[float, Number(gt=0.0, le=1.0)] = Field(
        0.8, description="Factor (-) on the automatic stable time step, in (0, 1]. Default: 0.8.")
    pd_loop: PdLoop = Field(
        "pairs", description='Peridynamic force loop: "pairs" (the particle-pair loop) or '
                             '"full_family" (the per-particle reference loop). Default: "pairs".')
    gravity: Annotated[Vec3, Vector("m/s^2")] = Field(
        (0.0, 0.0, 0.0), description="Gravitational acceleration (m/s^2). Default: [0, 0, 0].")
    title: Text = Field("", description="A title for the results file and plots. Default: none.")
    substeps: Annotated[int, Whole(0, "(0 = automatic)")] = Field(
        0, description="Steps of the faster side (ice or structures) per coupling step; "
                       "0 = automatic. Default: 0 (automatic).")
    short_range_contact: Boolean = Field(
        False, description="Repulsion between ice particles closer than 0.9 of their initial "
                           "distance (broken pieces, separate floes; seed Eq. 4 with Silling & "
                           "Askari's constant). Always on when an ice body has failure = "
                           "\"ice\" (crushed ice carries load through it). Default: false.")
    allow_unstable_time_step: Boolean = Field(
        False, description="Run with a time_step above the stable estimate (only a warning); "
                           "otherwise such a step is refused (exit 2). Default: false.")
    checkpoint_interval_steps: Annotated[int, Whole(0, "(0 = no step-based checkpoints)")] = Field(
        0, description="Write `<out>/checkpoint.h5` every so many coupling steps; 0 = never. "
                       "Default: 0.")
    checkpoint_interval_minutes: Annotated[float, Number("minutes", ge=0.0)] = Field(
        30.0, description="Write a checkpoint every so many minutes of wall time (minutes); "
                          "0 = never. Default: 30.")
    stability_check_interval_steps: Annotated[int, Whole(1)] = Field(
        10, description="Coupling steps between blow-up checks (NaN, runaway particles, energy "
                        "created beyond energy_tolerance). Default: 10.")
    energy_tolerance: Annotated[float, Number(gt=0.0, le=1.0)] = Field(
        0.01, description="Energy the run may create, as a fraction (-) of the energy supplied "
                          "(initial energy + work in, J), checked every "
                          "stability_check_interval_steps; halved when the step is above its "
                          "stable estimate. Crossing it stops the run (exit 3, with the energy "
                          "budget) once the created energy keeps growing, lasts with nothing "
                          "supplied to dilute it, or exceeds 10 x the limit; a transient that the "
                          "run's supply dilutes does not (docs/ice_failure.md, \"Energy guard\"). "
                          "In (0, 1]. Default: 0.01 (1 %).")
    output_per_rank: Boolean = Field(
        False, description="On several MPI ranks, each rank writes its own ice particles to "
                           "`results.rank<R>.h5` instead of sending them to rank 0 (for very large "
                           "runs). Default: false.")
    rebalance_every: Annotated[int, Whole(0, "(0 = never)")] = Field(
        0, description="On several MPI ranks, re-partition each split ice body every so many "
                       "coupling steps (recursive coordinate bisection of the current positions, "
                       "weighted by bond counts; particles and bonds move between ranks); 0 = "
                       "never. Not with output_per_rank. Default: 0.")
    rebalance_imbalance: Annotated[float, Number(ge=0.0)] = Field(
        0.0, description="On several MPI ranks, re-partition a split ice body when its largest "
                         "rank's work (bonds of its particles) exceeds the mean by this factor "
                         "(-), checked every coupling step, e.g. 1.2; 0 = never; else > 1. "
                         "Default: 0.")

    @model_validator(mode="after")
    def _interval_within_run(self) -> "RunSection":
        if self.output_interval is not None and self.output_interval > self.end_time:
            raise fail(f"longer than the run (end_time = {self.end_time:g} s); choose an interval "
                       "<= end_time", self.output_interval, key="output_interval")
        if self.output_interval is not None and \
                self.end_time / self.output_interval > MAX_FRAMES:
            raise fail(f"end_time / output_interval = {self.end_time / self.output_interval:.3g} "
                       f"frames, more than the {MAX_FRAMES:,} a run may write (each holds every "
                       "particle's fields); choose output_interval >= "
                       f"{self.end_time / MAX_FRAMES:.3g} s (end_time / {MAX_FRAMES:.0e})",
                       self.output_interval, key="output_interval")
        if 0.0 < self.rebalance_imbalance <= 1.0:
            raise fail("the largest over the mean work is at least 1; choose 0 (never) or a "
                       "factor > 1, e.g. 1.2", self.rebalance_imbalance, key="rebalance_imbalance")
        if self.output_per_rank and (self.rebalance_every or self.rebalance_imbalance):
            raise fail("re-partitioning moves particles between ranks, which output_per_rank "
                       "does not follow (each rank's file keeps the particles it had at the "
                       "start); set output_per_rank = false or rebalance_every = 0 and "
                       "rebalance_imbalance = 0", True, key="output_per_rank")
        return self
