"""The time loop of a run: build the bodies of a case, advance them, write results.

The driver knows the physics objects and the results writer, nothing of numba or MPI. It steps
every ice body with one global time step (the smallest stable step times the safety factor,
or the case's ``time_step``), writes a frame every ``output_interval`` and an energy history
(kinetic, strain, external work, and the energy taken out by broken bonds as the balance).
"""

from __future__ import annotations

import math
import sys
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import __version__
from .config import Case
from .errors import InstabilityError
from .io import ResultsWriter
from .fem.build import build_structure
from .fem.structure import ElasticStructure
from .pd.body import IceBody
from .pd.build import build_ice_body
from .progress import Progress


@dataclass
class RunSummary:
    """What a finished run reports (SI units)."""

    results: Path
    steps: int
    time_step: float
    end_time: float
    wall_seconds: float
    particles: int
    bonds: int
    broken_bonds: int
    frames: int

    def text(self) -> str:
        """A few lines for the terminal."""
        return (f"pdfem: {self.steps} steps of {self.time_step:.3e} s to t = {self.end_time:.4e} s "
                f"in {self.wall_seconds:.1f} s wall\n"
                f"  particles {self.particles:,}, bonds {self.bonds:,}, broken {self.broken_bonds:,}\n"
                f"  results: {self.results} ({self.frames} frames; open {self.results.with_suffix('.xdmf')} "
                "in ParaView)")


def critical_step(obj) -> float:
    """Stable-step limit (s) of an ice body (Silling & Askari) or a structure (2/omega_max)."""
    if isinstance(obj, IceBody):
        return obj.stable_time_step()
    if isinstance(obj, ElasticStructure):
        return obj.solver.critical_time_step()
    return math.inf  # rigid bodies move as prescribed


def choose_time_step(case: Case, bodies: list, log=print) -> float:
    """The global step (s): the case's ``time_step`` or safety_factor x the smallest stable step."""
    estimate = min(critical_step(b) for b in bodies)
    if not math.isfinite(estimate):
        estimate = case.run.output_interval / 10
    if case.run.time_step is None:
        return case.run.safety_factor * estimate
    if case.run.time_step > estimate:
        warnings.warn(f"{case.file}: run.time_step = {case.run.time_step:.3e} s exceeds the stable "
                      f"estimate {estimate:.3e} s (Silling & Askari); the run may blow up", stacklevel=2)
    return case.run.time_step


def _structure_fields(s) -> dict[str, np.ndarray]:
    if isinstance(s, ElasticStructure):
        return {"u": s.displacement(), "von_mises": s.von_mises()}
    return {"u": s.surface_points() - s.x0}


def _energies(bodies: list[IceBody]) -> dict[str, float]:
    kin = sum(b.kinetic_energy() for b in bodies)
    strain = sum(b.strain_energy() for b in bodies)
    pot = sum(b.gravity_potential() for b in bodies)
    work = sum(b.external_work for b in bodies)
    return {"kinetic": kin, "strain": strain, "gravity_potential": pot, "external_work": work}


def _check_finite(bodies: list[IceBody], t: float) -> None:
    for b in bodies:
        bad = ~np.isfinite(b.y).all(axis=1) | ~np.isfinite(b.v).all(axis=1)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            raise InstabilityError(
                f"the state of ice body '{b.name}' became NaN/Inf at t = {t:.4e} s "
                f"(first at particle {i}, reference position {b.x0[i].tolist()} m); "
                "the time step is probably too large: lower run.safety_factor or run.time_step")


def run_case(case: Case, out_dir: str | Path, *, quiet: bool = False, progress: bool | None = None,
             log=None) -> RunSummary:
    """Run a validated case and write ``results.h5`` (+ ``results.xdmf``) into ``out_dir``.

    Parameters
    ----------
    case
        The validated case (:func:`pdfem.config.load_case`).
    out_dir
        Output directory (created).
    quiet
        No messages on standard output and no progress line.
    progress
        Force the progress line on/off (default: when standard error is a terminal).
    log
        Function taking one string (default: print to standard output).

    Returns
    -------
    RunSummary
    """
    say = (lambda s: None) if quiet else (log or (lambda s: print(s, flush=True)))
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t_setup = time.perf_counter()
    bodies = [build_ice_body(cfg, case.run, case.file) for cfg in case.ice]
    structures = [build_structure(cfg, out, case.file) for cfg in case.structures]
    dt = choose_time_step(case, bodies + structures)
    end = case.run.end_time
    nsteps = max(1, math.ceil(end / dt - 1e-9))
    dt = end / nsteps
    n_part = sum(b.n for b in bodies)
    n_bonds = sum(b.n_bonds for b in bodies)
    mem = sum(b.n * 200 + b.n_bonds * 13 for b in bodies)
    say(f"pdfem {__version__}: {case.file}{(' - ' + case.run.title) if case.run.title else ''}")
    for b in bodies:
        say(f"  ice '{b.name}': {b.n:,} particles, {b.n_bonds:,} bonds, dx = {b.dx:g} m, "
            f"horizon = {b.delta:g} m, s0 = {b.s0:.3e}, stable step {b.stable_time_step():.3e} s")
    for st in structures:
        if isinstance(st, ElasticStructure):
            say(f"  structure '{st.name}': {st.mesh.n_nodes:,} nodes, {st.mesh.n_elements:,} {st.cell_type} "
                f"elements, critical step {st.solver.critical_time_step():.3e} s")
        else:
            say(f"  rigid body '{st.name}': {len(st.x0):,} surface nodes")
    say(f"  time step {dt:.3e} s, {nsteps:,} steps to {end:g} s; about {mem / 2**20:.0f} MiB of state")

    path = out / "results.h5"
    writer = ResultsWriter(path, case.text, {"title": case.run.title, "ranks": 1,
                                             "time_step": dt, "pd_loop": case.run.pd_loop})
    for b in bodies:
        writer.add_ice_body(b.name, b.x0, b.vol)
        b.start()
    for st in structures:
        if isinstance(st, ElasticStructure):
            writer.add_structure(st.name, st.points, st.cells, st.cell_type)
        else:
            writer.add_structure(st.name, st.x0, st.surface_triangles, "triangle")

    def frame(t: float) -> None:
        ice = {b.name: {"u": b.displacement(), "v": b.v, "damage": b.damage()} for b in bodies}
        if structures:
            writer.write_frame(t, ice, structures={st.name: _structure_fields(st) for st in structures})
        else:
            writer.write_frame(t, ice)
        for st in structures:
            if isinstance(st, ElasticStructure):
                hist = {"kinetic": st.kinetic_energy(), "strain": st.strain_energy()}
                for g in case.structures[structures.index(st)].fixed_groups:
                    hist[f"reaction_{g}"] = st.reaction(g)
                writer.append_history(f"structures/{st.name}", t, hist)
        if not bodies:
            return
        e = _energies(bodies)
        e0 = initial_energy
        e["dissipated"] = e0 + e["external_work"] - (e["kinetic"] + e["strain"] + e["gravity_potential"])
        writer.append_history("energy", t, e)

    initial_energy = sum(_energies(bodies)[k] for k in ("kinetic", "strain", "gravity_potential"))
    frame(0.0)
    frames = 1
    say(f"  set-up {time.perf_counter() - t_setup:.1f} s; running")
    bar = Progress(end, enabled=False if quiet else progress)
    next_out = case.run.output_interval
    broken = 0
    step = 0
    try:
        for step in range(1, nsteps + 1):
            for b in bodies:
                broken += b.step(dt)
            for st in structures:
                st.step(dt)
            t = step * dt
            if t >= next_out * (1 - 1e-9) or step == nsteps:
                _check_finite(bodies, t)
                frame(t)
                frames += 1
                while next_out <= t * (1 + 1e-9):
                    next_out += case.run.output_interval
            bar.update(t, step)
    finally:
        wall = bar.finish()
        writer.close()
    return RunSummary(path, step, dt, nsteps * dt, wall, n_part, n_bonds,
                      sum(int(b.broken.sum()) for b in bodies), frames)
