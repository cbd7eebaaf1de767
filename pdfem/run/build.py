"""Build a run from a case: ice bodies, structures, contact pairs, particle forces, coupler.

:func:`build` is the first of the driver's three steps (build -> loop -> finish, see
:mod:`pdfem.run.driver`). It translates the validated case into physics objects through the
builders of :mod:`pdfem.run` (ice: :func:`pdfem.run.build_ice.build_ice_body`; structures: the
kinds of :data:`pdfem.run.build_structures.STRUCTURE_KINDS`; particle forces: the kinds of
:data:`pdfem.run.build_forces.PARTICLE_FORCES`), checks what can only be checked on the built
objects (meshes, overlapping ice bodies, monitors off their structure, ice starting inside a
structure, the time step), splits the ice over the MPI
ranks and reports what it built with ``say``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pdfem.case.schema import Case
from pdfem.coupling.contact import SurfaceContact, overlapping
from pdfem.coupling.coupler import ContactPair, Coupler
from pdfem.errors import InputError
from pdfem.meshing.quality import MeshQualityError
from pdfem.run.build_forces import build_forces
from pdfem.run.build_ice import build_ice_body
from pdfem.run.parallel import build_structures, report_partitions
from pdfem.run.timesteps import choose_time_steps


@dataclass
class Setup:
    """A built run (SI units)."""

    bodies: list                 # ice bodies (whole, or this rank's part under MPI)
    structures: list             # pdfem.fem.base.Structure
    pairs: list                  # ContactPair
    forces: list                 # pdfem.forces.base.ParticleForce
    coupler: Coupler
    probes: list                 # (monitor name, structure, probe)
    dt: float                    # coupling step, s
    n_ice: int                   # ice substeps per coupling step
    n_st: int                    # structure substeps per coupling step
    nsteps: int                  # coupling steps to the end time
    stable: dict[str, float]     # stable step of each ice body, s
    particles: int
    bonds: int
    cut: int                     # bonds broken before the run (pre-cracks)


def check_mesh(st, cfg, file: str) -> None:
    """Refuse a structure whose mesh has bad elements (exit 2), naming its case field."""
    try:
        st.check_mesh()
    except MeshQualityError as exc:
        raise InputError(file, f"{cfg.field}.mesh", f"the mesh of structure '{st.name}' has bad "
                         f"elements: {exc}; fix or re-mesh it", cfg.mesh) from None


def check_overlaps(case: Case, bodies: list) -> None:
    """Refuse ice bodies that overlap: bounding boxes first, then whether a particle of one
    lies inside the other's shape (bodies that only touch, face to face, are valid).

    Raises
    ------
    InputError
        Naming both bodies (the field of the later one's shape) and the overlap box (m).
    """
    for j, (b, cb) in enumerate(zip(bodies, case.ice)):
        for a, ca in zip(bodies[:j], case.ice[:j]):
            lo = np.maximum(*(c.shape.bounds()[0] for c in (ca, cb)))
            hi = np.minimum(*(c.shape.bounds()[1] for c in (ca, cb)))
            if np.any(hi <= lo):
                continue  # bounding boxes apart or touching
            inside = np.concatenate([cb.shape.contains(a.x0[_in_box(a.x0, lo, hi)]),
                                     ca.shape.contains(b.x0[_in_box(b.x0, lo, hi)])])
            if inside.any():
                raise InputError(case.file, f"{cb.field}.shape",
                                 f"ice bodies '{ca.name}' and '{cb.name}' overlap "
                                 f"({int(inside.sum()):,} particles of one lie inside the other) "
                                 f"in the box min = {lo.round(6).tolist()}, max = "
                                 f"{hi.round(6).tolist()} m; move or shrink one of them (bodies "
                                 "may touch but not overlap)")


def _in_box(x: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Whether each point of ``x`` (N, 3) lies in the box ``lo``..``hi`` (m)."""
    return np.all((x >= lo) & (x <= hi), axis=1)


def make_probes(case: Case, structures: list) -> list:
    """``(monitor name, structure, probe)`` of every monitor, refused when the point lies
    farther from its structure's nearest node than the size of the element there (the
    diagonal of its bounding box).

    Raises
    ------
    InputError
        Naming the monitor's point field, the distance and the element size (m).
    """
    by_name = {s.name: s for s in structures}
    probes = []
    for m in case.monitors:
        st = by_name[m.structure]
        probe = st.probe(m.point)
        points, cells, _ = st.output_mesh()
        size = float(np.linalg.norm(np.ptp(points[cells[probe.element]], axis=0)))
        gap = float(np.linalg.norm(points[probe.node] - np.asarray(m.point)))
        if gap > size:
            raise InputError(case.file, f"{m.field}.point",
                             f"the point is {gap:.4g} m from the nearest node of structure "
                             f"'{st.name}' ({points[probe.node].round(6).tolist()} m), more than "
                             f"the element size there ({size:.4g} m): it is not on the "
                             "structure; give a point on or in it (m)", list(m.point))
        probes.append((m.name, st, probe))
    return probes


def contact_pairs(case: Case, bodies: list, structures: list, comm) -> list[ContactPair]:
    """The case's contact pairs, refused if the structure has no contact surface or the ice
    starts inside it; their contact weights are summed over ``comm``'s ranks."""
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
                                 SurfaceContact(st, radius, c.friction, name=c.name,
                                                reduce=comm.allreduce_sum)))
    return pairs


def build(case: Case, out: Path, comm, say, steps: tuple[float, int, int] | None = None) -> Setup:
    """Build the run of ``case`` on this rank (collective under MPI).

    Parameters
    ----------
    case
        The validated case.
    out
        The output directory (structure models are meshed into it).
    comm
        The communicator (:func:`pdfem.parallel.comm.world`).
    say
        Function taking one line of the start-up report.
    steps
        ``(coupling step, ice substeps, structure substeps)`` to use instead of the chosen
        ones (a restart continues with the steps it was started with).

    Raises
    ------
    InputError
        Bad input found while building.
    """
    bodies = [build_ice_body(cfg, case.run, case.file, comm) for cfg in case.ice]
    structures = build_structures(case.structures, out, case.file, comm)
    for st, cfg in zip(structures, case.structures):
        check_mesh(st, cfg, case.file)
    check_overlaps(case, bodies)
    probes = make_probes(case, structures)
    dt, n_ice, n_st = choose_time_steps(case, bodies, structures)
    stable = {b.name: b.stable_time_step() for b in bodies}
    sizes = [b.counts() for b in bodies]
    for b, (n, nb, _) in zip(bodies, sizes):
        say(f"  ice '{b.name}': {n:,} particles, {nb:,} bonds, dx = {b.dx:g} m, "
            f"horizon = {b.delta:g} m, s0 = {b.s0:.3e}, stable step {stable[b.name]:.3e} s")
    counts = tuple(sum(c) for c in zip(*sizes)) if sizes else (0, 0, 0)
    report_partitions(bodies, comm, say)
    pairs = contact_pairs(case, bodies, structures, comm)
    if steps is not None:
        dt, n_ice, n_st = steps
    end = case.run.end_time
    nsteps = max(1, round(end / dt))
    for st in structures:
        say(f"  {st.describe()}")
    for p in pairs:
        say(f"  contact '{p.name}': ice '{p.body.name}' on structure '{p.structure.name}', "
            f"search radius {p.contact.search_radius:g} m, friction {p.contact.friction:g}")
    sub = ""
    if n_ice > 1:
        sub = f" (ice subcycles: {n_ice} steps of {dt / n_ice:.3e} s)"
    elif n_st > 1:
        sub = f" (structures subcycle: {n_st} steps of {dt / n_st:.3e} s)"
    say(f"  coupling step {dt:.3e} s{sub}, {nsteps:,} steps to {end:g} s")
    forces = build_forces(case, bodies)
    coupler = Coupler(bodies, structures, pairs, dt, n_ice, n_st, forces, comm)
    return Setup(bodies, structures, pairs, forces, coupler, probes, dt, n_ice, n_st, nsteps,
                 stable, *counts)
