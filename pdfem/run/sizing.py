"""``pdfem run CASE --estimate``: size a run without building it (memory, time per step, wall time).

Memory per rank and per node comes from :mod:`pdfem.run.preflight` (lattice counts, no particle
is generated). Time: a short calibration measures this machine's ice step rate in bond-steps
per second: a cube of ``CALIBRATION_SIDE``^3 particles with the case's first ice material, dx,
horizon, failure law and PD loop is built and stepped for ``CALIBRATION_SECONDS`` (a lattice of
about 1.8 M bonds: larger than the processor caches, so the rate is the large-body rate; about
0.5 s of stepping plus a second of set-up). The stable ice step comes from a piece of each body:
a box of its lattice, ``STABLE_STEP_SIDE`` particles per axis at most (a thin sheet stays as
thin, so its surface-corrected particles are there), so the ice steps to ``end_time`` are
``ceil(end_time / dt)`` with ``dt`` the case's ``time_step`` or ``safety_factor`` x the stable
step. The time per step is the largest rank's bonds over the rate (each rank with this
process's numba threads); the halo exchange (4 % of the step on 2 ranks here, BENCHMARKS.md),
structures and contact are not counted. Units: SI (s, bytes).
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass

import numba

from pdfem.case.schema import Case
from pdfem.errors import InputError
from pdfem.geometry.shapes import Box
from pdfem.parallel.nodes import block_layout, node_layout, per_node
from pdfem.pd.body import IceBody
from pdfem.pd.failure import failure_law
from pdfem.run.build_ice import ice_material
from pdfem.run.estimates import available_memory, format_bytes, lattice_counts
from pdfem.run.preflight import (SETUP_TEXT, body_lines, check_nodes, estimate_rank_memory,
                                 node_lines, node_needs, rank_table)
from pdfem.run.step_limits import check_ice_steps

CALIBRATION_SIDE = 32
"""Particles per side of the calibration cube (32^3 = 32,768 particles, about 1.6 M bonds)."""

STABLE_STEP_SIDE = 12
"""Particles per axis (at most the body's own count) of the piece of each body giving its
stable step: two horizons, so it holds every kind of particle a box body has (interior, faces,
edges, corners, with their surface correction)."""

CALIBRATION_SECONDS = 0.5
"""How long the calibration cube is stepped (s of wall time, after one untimed step)."""

_UNITS = {"": 1, "B": 1, "K": 2**10, "M": 2**20, "G": 2**30, "T": 2**40,
          "KB": 10**3, "MB": 10**6, "GB": 10**9, "TB": 10**12,
          "KIB": 2**10, "MIB": 2**20, "GIB": 2**30, "TIB": 2**40}


def parse_bytes(text: str) -> int:
    """``"24GB"`` (10^9), ``"24GiB"`` or ``"24G"`` (2^30), ``"2.5e10"`` as bytes.

    Raises
    ------
    InputError
        Naming ``--node-memory`` and the valid forms.
    """
    m = re.fullmatch(r"\s*([0-9.]+(?:[eE][+-]?[0-9]+)?)\s*([A-Za-z]*)\s*", str(text))
    unit = m.group(2).upper() if m else None
    if m is None or unit not in _UNITS:
        raise InputError(None, "--node-memory", "give the memory of one node as a number of bytes "
                         "with an optional unit: 24GB (10^9 bytes), 24GiB or 24G (2^30 bytes), "
                         "512MB, 2.5e10", text)
    return int(float(m.group(1)) * _UNITS[unit])


def _cube(cfg, run, side: int, clip: bool = False) -> IceBody:
    """A box of ``side`` particles per axis (with ``clip``, at most the body's own lattice
    count per axis, so a thin sheet gives a piece as thin) with the material, dx, horizon and
    failure law of ``cfg``."""
    lo, hi = cfg.shape.bounds()
    material = ice_material(cfg.material, cfg.dx, float(hi[2] - lo[2]))
    law = failure_law(cfg.material.failure, material, cfg.horizon)
    counts = lattice_counts(cfg.shape, cfg.dx) if clip else (side,) * 3
    box = Box((0.0, 0.0, 0.0), tuple(min(side, c) * cfg.dx for c in counts))
    return IceBody.from_shape("calibration", box, material, cfg.dx, cfg.horizon,
                              loop=run.pd_loop, failure=law)


@dataclass(frozen=True)
class Calibration:
    """This machine's ice step: bond-steps per second and the stable ice step (s)."""

    bond_steps_per_s: float
    ice_step: float
    bonds: int
    threads: int


def calibrate(case: Case, seconds: float = CALIBRATION_SECONDS) -> Calibration:
    """Measure the bond-step rate on the calibration cube and the case's ice step (module
    docstring); no case body is built.

    Raises
    ------
    InputError
        If the ice would take more steps than a run can finish
        (:func:`pdfem.run.step_limits.check_ice_steps`).
    """
    run = case.run
    stable = [_cube(c, run, STABLE_STEP_SIDE, clip=True).stable_time_step() for c in case.ice]
    check_ice_steps(case, stable)
    body = _cube(case.ice[0], run, CALIBRATION_SIDE)
    dt = run.time_step if run.time_step is not None else run.safety_factor * min(stable)
    body.start()
    body.step(dt)  # untimed: touches the scratch memory
    steps, t0 = 0, time.perf_counter()
    while steps < 3 or time.perf_counter() - t0 < seconds:
        body.step(dt)
        steps += 1
    rate = body.n_bonds * steps / (time.perf_counter() - t0)
    return Calibration(rate, dt, body.n_bonds, numba.get_num_threads())


def _hours(s: float) -> str:
    return f"{s:.3g} s" if s < 120 else (f"{s / 60:.1f} min" if s < 7200 else f"{s / 3600:.1f} h")


def estimate_report(case: Case, comm, ranks: int | None = None, nodes: int | None = None,
                    node_memory: int | None = None, distributed: bool = False
                    ) -> tuple[list[str], InputError | None]:
    """The dry run of ``pdfem run --estimate`` (collective under MPI): report lines and the
    refusal (None when every node holds its ranks).

    Parameters
    ----------
    case
        The validated case.
    comm
        The communicator (its size and nodes are the layout when neither ``ranks`` nor
        ``nodes`` is given).
    ranks, nodes
        A planned layout: ``ranks`` ranks (default: the world's size) on ``nodes`` nodes
        (default 1), ``ceil(ranks / nodes)`` per node.
    node_memory
        Bytes available per node (default: ``MemAvailable`` of each node; of this machine
        for a planned layout).
    distributed
        Estimate for the distributed set-up (else today's global set-up).
    """
    if ranks is None and nodes is None:
        n = comm.size
        layout = node_layout(comm)
        avail = per_node(comm, layout, available_memory)
    else:
        n = ranks or comm.size
        layout = block_layout(n, nodes or 1)
        avail = [available_memory()] * (max(layout) + 1)
    if node_memory is not None:
        avail = [node_memory] * len(avail)
    est = estimate_rank_memory(case, n, distributed)
    lines = [f"pdfem run --estimate: {case.file}: {n} rank{'s' if n > 1 else ''} on "
             f"{max(layout) + 1} node{'s' if max(layout) else ''}",
             f"  {SETUP_TEXT[distributed]}"]
    lines += body_lines(case) + rank_table(est, layout) + node_lines(est, layout, avail)
    if case.ice:
        cal = calibrate(case)
        rate = min(comm.allgather(cal.bond_steps_per_s))
        per_step = max(r.bonds for r in est) / rate
        steps = max(1, math.ceil(case.run.end_time / cal.ice_step - 1e-9))
        lines += [f"  this machine: {rate / 1e6:.1f} M bond-steps/s per rank with {cal.threads} "
                  f"thread{'s' if cal.threads > 1 else ''} (calibration cube of {cal.bonds:,} "
                  "bonds)",
                  f"  ice step {cal.ice_step:.3e} s: {steps:,} steps to end_time = "
                  f"{case.run.end_time:g} s, about {per_step:.3g} s per step (bond work of the "
                  f"largest rank), projected wall time {_hours(steps * per_step)}"]
    try:
        check_nodes(case, est, layout, avail, distributed)
    except InputError as exc:
        return lines + ["  refused: does not fit (see below)"], exc
    need = max(node_needs(est, layout))
    lines.append(f"  fits: every node holds its ranks (largest need {format_bytes(need)})")
    return lines, None
