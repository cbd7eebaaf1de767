"""The time loop of a run: build the bodies of a case, advance them together, write results.

The driver knows the physics objects, the coupler and the results writer, nothing of numba or
MPI. Each coupling step (:class:`pdfem.coupling.coupler.Coupler`) advances the structures and
the ice bodies, the faster side subcycling, with surface-element contact between the pairs the
case names. Results: a frame every ``output_interval`` (ice and structure fields, energies,
structure reactions), and at every coupling step the ice load on each structure (force,
moment, particles in contact) and the monitor probes.

Around the loop: up-front estimates of particles, bonds and memory (a run that cannot fit is
refused before anything is allocated), the time-step check (a ``run.time_step`` above the
stable estimate is bad input unless ``run.allow_unstable_time_step``), checkpoints and
restart (:mod:`pdfem.run.checkpoint`; the results file is continued in place), and blow-up
detection (:mod:`pdfem.run.blowup`; exit 3 with the results so far kept).
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pdfem import __version__
from pdfem.case.schema import Case
from pdfem.coupling.contact import SurfaceContact, overlapping
from pdfem.coupling.coupler import ContactPair, Coupler, substep_counts
from pdfem.forces.short_range import ShortRangeContact
from pdfem.parallel.comm import world
from pdfem.run.parallel import (build_structures, distribute, gather_frame, owned_frame,
                       owned_reference)
from pdfem.run.blowup import BlowupMonitor
from pdfem.run.checkpoint import CHECKPOINT_NAME, DriverState, read_checkpoint, restore, write_checkpoint
from pdfem.errors import InputError, InstabilityError
from pdfem.run.estimates import (FIXED_BYTES, BodyEstimate, available_memory, estimate_body,
                        format_bytes)
from pdfem.output.results import ResultsWriter, rank_file
from pdfem.meshing.quality import MeshQualityError, check_cells
from pdfem.fem.structure import ElasticStructure
from pdfem.pd.body import IceBody
from pdfem.run.build_ice import build_ice_body
from pdfem.run.progress import Progress


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
    """Stable-step limit (s) of an ice body (the smaller of Silling & Askari's estimate and a
    guaranteed bound) or a structure (2/omega_max); ``inf`` for a rigid body."""
    if isinstance(obj, IceBody):
        return obj.stable_time_step()
    if isinstance(obj, ElasticStructure):
        return obj.solver.critical_time_step()
    return math.inf  # rigid bodies move as prescribed


def choose_time_steps(case: Case, bodies: list, structures: list) -> tuple[float, int, int]:
    """The coupling step (s) and the substeps of the ice and of the structures per step.

    The ice step is the case's ``time_step`` or safety_factor x the smallest stable ice step;
    the structure step is safety_factor x the smallest critical structure step. The faster side
    subcycles (:func:`pdfem.coupling.coupler.substep_counts`); ``run.substeps`` overrides the
    count. The coupling step is then shortened so that a whole number of steps ends the run.

    Raises
    ------
    InputError
        If ``run.time_step`` exceeds the stable ice step and the case does not set
        ``run.allow_unstable_time_step = true`` (with it: a warning).
    """
    run = case.run
    ice = min((critical_step(b) for b in bodies), default=math.inf)
    if run.time_step is not None:
        if run.time_step > ice:
            worst = min(bodies, key=critical_step).name
            if not run.allow_unstable_time_step:
                raise InputError(case.file, "run.time_step",
                                 f"exceeds the stable step {ice:.4e} s of ice body '{worst}' "
                                 f"({run.time_step / ice:.2f} x), so the run would blow up; "
                                 f"choose time_step <= {ice:.4e} s, leave it out (automatic "
                                 "step), or set run.allow_unstable_time_step = true to run "
                                 "anyway", run.time_step)
            warnings.warn(f"{case.file}: run.time_step = {run.time_step:.3e} s exceeds the stable "
                          f"ice step {ice:.3e} s of '{worst}' (allowed by "
                          "run.allow_unstable_time_step); the run may blow up", stacklevel=2)
        ice = run.time_step
    else:
        ice *= run.safety_factor
    st = run.safety_factor * min((critical_step(s) for s in structures), default=math.inf)
    if not math.isfinite(ice) and not math.isfinite(st):
        ice = run.output_interval / 10  # rigid bodies only
    dt, n_ice, n_st = substep_counts(ice, st, run.substeps)
    nsteps = max(1, math.ceil(run.end_time / dt - 1e-9))
    return run.end_time / nsteps, n_ice, n_st


def estimate_case(case: Case) -> list[BodyEstimate]:
    """Particles, pairs and memory of every ice body of a case, before building
    (:func:`pdfem.run.estimates.estimate_body`)."""
    return [estimate_body(c.name, c.shape, c.dx, c.horizon) for c in case.ice]


def check_memory(case: Case, estimates: list[BodyEstimate], available: int | None) -> int:
    """The estimated memory (bytes) of the run; refuse it if it exceeds ``available`` bytes.

    Raises
    ------
    InputError
        Naming the body that needs most, with the estimate and what is available.
    """
    need = FIXED_BYTES + sum(e.bytes for e in estimates)
    if available is not None and estimates and need > available:
        big = max(range(len(estimates)), key=lambda k: estimates[k].bytes)
        e = estimates[big]
        raise InputError(case.file, f"{case.ice[big].field}.dx",
                         f"the run needs about {format_bytes(need)} of memory but "
                         f"{format_bytes(available)} is available; ice body '{e.name}' alone has "
                         f"about {e.particles:,} particles and {e.pairs:,} bonds "
                         f"({format_bytes(e.bytes)}); choose a larger dx, a smaller body, or a "
                         "machine with more memory", case.ice[big].dx)
    return need


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


def _system_energies(structures: list, coupler: Coupler) -> dict[str, float]:
    """Energies (J) of the elastic structures, and the work done on the ice by rigid bodies
    (minus the work of the contact loads on them)."""
    elastic = [s for s in structures if isinstance(s, ElasticStructure)]
    return {"structure_kinetic": sum(s.kinetic_energy() for s in elastic),
            "structure_strain": sum(s.strain_energy() for s in elastic),
            "short_range_potential": (coupler.short_range.potential_energy()
                                      if coupler.short_range is not None else 0.0),
            "rigid_body_work": -sum(coupler.contact_work[id(s)] for s in structures
                                    if not isinstance(s, ElasticStructure))}


def _contact_pairs(case: Case, bodies: list[IceBody], structures: list) -> list[ContactPair]:
    by_name = {b.name: b for b in bodies} | {s.name: s for s in structures}
    pairs = []
    for c in case.contacts:
        body, st = by_name[c.ice], by_name[c.structure]
        if len(st.surface_triangles) == 0:
            raise InputError(case.file, f"{c.field or 'contact'}.structure",
                             f"structure '{st.name}' has no contact surface (its contact_group "
                             "names no faces)", c.structure)
        radius = c.search_radius or 0.5 * body.dx
        depth = max(radius, body.delta)
        inside = overlapping(st, body.y, depth)
        if inside.any():
            i = int(np.flatnonzero(inside)[0])
            raise InputError(case.file, c.field or "contact",
                             f"{int(inside.sum())} particles of ice '{body.name}' start inside "
                             f"structure '{st.name}' (behind its contact surface, up to {depth:g} m "
                             f"deep; the first at {body.x0[i].round(6).tolist()} m); move the ice "
                             "or the structure so that they start apart")
        pairs.append(ContactPair(c.name, body, st,
                                 SurfaceContact(st, radius, c.friction, name=c.name)))
    return pairs


def _check_elements(st, cfg, file: str) -> None:
    """Refuse inverted or degenerate tetrahedra of an elastic structure's mesh (exit 2)."""
    if not isinstance(st, ElasticStructure) or st.cell_type != "tetra":
        return
    try:
        check_cells(st.points, st.cells, 3)
    except MeshQualityError as exc:
        raise InputError(file, f"{cfg.field}.mesh", f"the mesh of structure '{st.name}' has bad "
                         f"elements: {exc}; fix or re-mesh it", cfg.mesh) from None


def _finite_state(bodies: list, structures: list) -> bool:
    """Whether every ice position and velocity and every structure displacement is finite."""
    return (all(np.isfinite(b.y).all() and np.isfinite(b.v).all() for b in bodies)
            and all(np.isfinite(s.displacement()).all() for s in structures
                    if isinstance(s, ElasticStructure)))


class NullWriter:
    """The results writer of MPI ranks other than 0: rank 0 writes the file."""

    n_frames = 0

    def __getattr__(self, name):
        return lambda *args, **kwargs: None


def _open_results(path: Path, case_text: str, meta: dict, append: bool) -> ResultsWriter:
    """A new results file, or (``append``, a restart) the existing one reopened."""
    if not append:
        return ResultsWriter(path, case_text, meta)
    try:
        return ResultsWriter(path, case_text, append=True)
    except (OSError, ValueError) as exc:
        raise InputError(str(path), "--restart", f"cannot continue this results file ({exc}); "
                         "give the output directory of the run that wrote the checkpoint with "
                         "--out (a run with run.output_per_rank restarts on as many ranks)"
                         ) from None


def run_case(case: Case, out_dir: str | Path, *, quiet: bool = False, progress: bool | None = None,
             log=None, restart: str | Path | None = None) -> RunSummary:
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
        Output directory (created).
    quiet
        No messages on standard output and no progress line.
    progress
        Force the progress line on/off (default: when standard error is a terminal).
    log
        Function taking one string (default: print to standard output).
    restart
        A checkpoint of this case to continue from; the run appends to ``out_dir/results.h5``
        (frames and history rows written after the checkpoint are dropped).

    Returns
    -------
    RunSummary

    Raises
    ------
    InputError
        Bad input (including a run too large for the memory, an unstable ``run.time_step``, a
        checkpoint of another case).
    InstabilityError
        The run blew up; the results file holds every frame up to then (and one at the
        failure when the state is still finite).
    """
    comm = world()
    quiet = quiet or comm.rank != 0  # one rank speaks for all
    say = (lambda s: None) if quiet else (log or (lambda s: print(s, flush=True)))
    out = Path(out_dir)
    ckpt = read_checkpoint(restart, case.text, case.file) if restart is not None else None
    estimates = estimate_case(case)
    available = available_memory()
    need = check_memory(case, estimates, available)
    say(f"pdfem {__version__}: {case.file}{(' - ' + case.run.title) if case.run.title else ''}")
    for e in estimates:
        say(f"  estimate for ice '{e.name}': {e.particles:,} particles, {e.pairs:,} bonds "
            f"({e.pairs_per_interior_particle} per interior particle"
            f"{'' if e.exact else ', an upper bound'}), {format_bytes(e.bytes)}")
    if estimates:
        say(f"  estimated memory {format_bytes(need)} of {format_bytes(available) if available else 'unknown'} "
            "available")
    out.mkdir(parents=True, exist_ok=True)
    t_setup = time.perf_counter()
    bodies = [build_ice_body(cfg, case.run, case.file) for cfg in case.ice]
    structures = build_structures(case.structures, out, case.file, comm)
    for st, cfg in zip(structures, case.structures):
        _check_elements(st, cfg, case.file)
    st_by_name = {s.name: s for s in structures}
    probes = []
    for m in case.monitors:
        st = st_by_name[m.structure]
        probes.append((m, st, st.probe(m.point)))
    dt, n_ice, n_st = choose_time_steps(case, bodies, structures)
    stable = {b.name: b.stable_time_step() for b in bodies}
    n_part = sum(b.n for b in bodies)
    n_bonds = sum(b.n_bonds for b in bodies)
    for b in bodies:
        say(f"  ice '{b.name}': {b.n:,} particles, {b.n_bonds:,} bonds, dx = {b.dx:g} m, "
            f"horizon = {b.delta:g} m, s0 = {b.s0:.3e}, stable step {stable[b.name]:.3e} s")
    reference = {b.name: (b.x0, b.vol) for b in bodies}
    cut = sum(int(b.broken.sum()) for b in bodies)  # bonds broken before the run (pre-cracks)
    bodies = distribute(bodies, comm, say)
    pairs = _contact_pairs(case, bodies, structures)
    if ckpt is not None:  # continue with the steps the run was started with
        dt, n_ice, n_st = (ckpt.driver.time_step, ckpt.driver.ice_substeps,
                           ckpt.driver.structure_substeps)
    end = case.run.end_time
    nsteps = max(1, round(end / dt))
    for st in structures:
        if isinstance(st, ElasticStructure):
            say(f"  structure '{st.name}': {st.mesh.n_nodes:,} nodes, {st.mesh.n_elements:,} {st.cell_type} "
                f"elements, critical step {st.solver.critical_time_step():.3e} s")
        else:
            say(f"  rigid body '{st.name}': {len(st.x0):,} surface nodes")
    for p in pairs:
        say(f"  contact '{p.name}': ice '{p.body.name}' on structure '{p.structure.name}', "
            f"search radius {p.contact.search_radius:g} m, friction {p.contact.friction:g}")
    sub = ""
    if n_ice > 1:
        sub = f" (ice subcycles: {n_ice} steps of {dt / n_ice:.3e} s)"
    elif n_st > 1:
        sub = f" (structures subcycle: {n_st} steps of {dt / n_st:.3e} s)"
    say(f"  coupling step {dt:.3e} s{sub}, {nsteps:,} steps to {end:g} s")

    path = out / "results.h5"
    ckpt_path = out / CHECKPOINT_NAME
    # with run.output_per_rank each rank writes its own particles to results.rank<R>.h5 (no
    # gathering), and rank 0 the rest to results.h5; read_results puts them together
    per_rank = case.run.output_per_rank and comm.size > 1
    meta = {"title": case.run.title, "ranks": comm.size, "time_step": dt, "ice_substeps": n_ice,
            "structure_substeps": n_st, "pd_loop": case.run.pd_loop}
    if per_rank:
        meta["ice_per_rank"] = comm.size
    writer = (_open_results(path, case.text, meta, ckpt is not None) if comm.rank == 0
              else NullWriter())
    ice_writer = writer
    if per_rank:
        ice_writer = _open_results(rank_file(path, comm.rank), case.text,
                                   {"rank": comm.rank, "ranks": comm.size}, ckpt is not None)
    try:
        for b in bodies:
            if per_rank:
                index, x0, vol = owned_reference(b)
                ice_writer.add_ice_body(b.name, x0, vol, index=index)
            else:
                ice_writer.add_ice_body(b.name, *reference[b.name])
    except ValueError as exc:  # only when appending: the file holds other particles
        raise InputError(str(ice_writer.path), "--restart", f"the results file does not fit "
                         f"this run ({exc}); a run with run.output_per_rank restarts on as many "
                         "ranks as wrote it") from None
    for st in structures:
        if isinstance(st, ElasticStructure):
            writer.add_structure(st.name, st.points, st.cells, st.cell_type)
        else:
            writer.add_structure(st.name, st.x0, st.surface_triangles, "triangle")
    short_range = (ShortRangeContact(bodies) if case.run.short_range_contact and bodies
                   else None)
    coupler = Coupler(bodies, structures, pairs, dt, n_ice, n_st, short_range,
                      comm if comm.size > 1 else None)
    monitor = BlowupMonitor(bodies, dt / n_ice, stable, case.run.stability_check_interval_steps,
                            energy_check=not any(cfg.loads for cfg in case.structures))

    def frame(t: float) -> dict[str, float]:
        if per_rank:
            ice_writer.write_frame(t, {b.name: owned_frame(b) for b in bodies})
            ice = {}
        else:
            ice = {b.name: gather_frame(b) for b in bodies}  # collective under MPI
        writer.write_frame(t, ice, structures={st.name: _structure_fields(st) for st in structures})
        e = _energies(bodies)
        for st, cfg in zip(structures, case.structures):
            if isinstance(st, ElasticStructure):
                hist = {"kinetic": st.kinetic_energy(), "strain": st.strain_energy()}
                for g in cfg.fixed_groups:
                    hist[f"reaction_{g}"] = st.reaction(g)
                writer.append_history(f"structures/{st.name}", t, hist)
        if not bodies:
            return {}
        e.update(_system_energies(structures, coupler))
        total = e["kinetic"] + e["strain"] + e["gravity_potential"] + e["structure_kinetic"] \
            + e["structure_strain"] + e["short_range_potential"]
        e["dissipated"] = initial_energy + e["external_work"] + e["rigid_body_work"] - total
        e["contact_dissipated"] = coupler.contact_dissipated
        e["fracture_dissipated"] = e["dissipated"] - e["contact_dissipated"]
        writer.append_history("energy", t, e)
        e["supplied"] = initial_energy + e["external_work"] + e["rigid_body_work"]
        return e

    def loads(t: float) -> None:
        for st in structures:
            if any(p.structure is st for p in pairs):
                force, moment, n = coupler.structure_load(st)
                writer.append_history(f"loads/{st.name}", t,
                                      {"force": force, "moment": moment, "contacts": n})
        for p in pairs:
            writer.append_history(f"contacts/{p.name}", t,
                                  {"force": p.force, "moment": p.moment, "contacts": p.contacts})
        for m, st, pr in probes:
            u, vm = st.probe_values(pr)
            writer.append_history(f"monitors/{m.name}", t, {"u": u, "von_mises": vm})

    try:
        if ckpt is None:
            coupler.start()
            initial_energy = (sum(_energies(bodies)[k] for k in ("kinetic", "strain",
                                                                  "gravity_potential"))
                              + sum(_system_energies(structures, coupler)[k]
                                    for k in ("structure_kinetic", "structure_strain",
                                              "short_range_potential")))
            frame(0.0)
            loads(0.0)
            frames, next_out, broken, first = 1, case.run.output_interval, 0, 1
        else:
            restore(ckpt, bodies, structures, coupler)
            d = ckpt.driver
            try:
                writer.resume(d.frames, d.history_rows)
                if per_rank:
                    ice_writer.resume(d.frames, {})
            except ValueError as exc:
                raise InputError(str(path), "--restart", f"the results file does not hold the "
                                 f"data up to the checkpoint ({exc})") from None
            initial_energy = d.initial_energy
            frames, next_out, broken, first = d.frames, d.next_output, d.broken, d.step + 1
            say(f"  restarting from {ckpt.path} at t = {d.time:.6e} s (step {d.step:,}), "
                f"appending to {path}")
    except BaseException:
        writer.close()
        ice_writer.close()
        raise
    every = case.run.checkpoint_interval_steps
    minutes = case.run.checkpoint_interval_minutes
    if every or minutes:
        when = " and ".join(w for w in ((f"every {every:,} steps" if every else ""),
                                        (f"every {minutes:g} min" if minutes else "")) if w)
        say(f"  checkpoints {when} to {ckpt_path}")
    say(f"  set-up {time.perf_counter() - t_setup:.1f} s; running")
    bar = Progress(end, enabled=False if quiet else progress)
    last_checkpoint = time.monotonic()
    step = first - 1
    t = step * dt
    last_frame = t
    try:
        for step in range(first, nsteps + 1):
            t = step * dt
            try:
                broken += coupler.step()
            except FloatingPointError as exc:
                monitor.check_motion(t, step, force=True)
                raise InstabilityError(f"at t = {t:.6e} s (step {step:,}): {exc}") from None
            loads(t)
            monitor.check_motion(t, step)
            if t >= next_out * (1 - 1e-9) or step == nsteps:
                monitor.check_motion(t, step, force=True)
                e = frame(t)
                last_frame = t
                frames += 1
                while next_out <= t * (1 + 1e-9):
                    next_out += case.run.output_interval
                if e:
                    monitor.check_energy(t, step, -e["dissipated"], e["supplied"])
            due = bool(every) and step % every == 0
            if minutes and not due:  # rank 0's clock decides for all ranks
                due = comm.bcast(time.monotonic() - last_checkpoint >= 60 * minutes)
            if step < nsteps and due:
                writer.flush()
                ice_writer.flush()
                write_checkpoint(ckpt_path, case.text,
                                 DriverState(step, t, dt, n_ice, n_st, next_out, frames, broken,
                                             initial_energy, writer.history_rows()),
                                 bodies, structures, coupler, comm.rank)
                last_checkpoint = time.monotonic()
            bar.update(t, step)
    except InstabilityError as exc:
        note = ""
        if comm.size == 1 and t > last_frame and _finite_state(bodies, structures):
            try:
                frame(t)
                note = f", the last at the failure, t = {t:.6e} s"
            except Exception:  # the diagnosis matters more than this last frame
                note = ""
        writer.close()
        ice_writer.close()
        raise InstabilityError(f"{exc}. The results so far are kept: {path} "
                               f"({writer.n_frames} frames{note})") from None
    finally:
        wall = bar.finish()
        writer.close()
        ice_writer.close()
    return RunSummary(path, step, dt, nsteps * dt, wall, n_part, n_bonds, cut + broken, frames)
