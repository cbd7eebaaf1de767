"""The case-file schema: one pydantic model per section, and the case the run reads.

A case file describes one run in SI units (m, kg, s, Pa, J/m^2). Every field is declared once,
with its meaning, unit and default, in a section model (:mod:`pdfem.case.run`,
:mod:`pdfem.case.ice`, :mod:`pdfem.case.structure`, :mod:`pdfem.case.links`,
:mod:`pdfem.case.shapes`; the whole file is :class:`CaseFile`). Loading
(:mod:`pdfem.case.loader`) validates a file once, before anything is built; an invalid or
unknown field raises :class:`pdfem.errors.InputError` naming the file, the field, the value and
what would be valid. The validated case (:mod:`pdfem.case.config`) is what :mod:`pdfem.run`
reads. :func:`json_schema` is the JSON Schema of the file (``pdfem schema``). Case files are
data: nothing in them is evaluated, but a ``.py`` model script named by a structure's ``mesh``
is executed (Python code, :mod:`pdfem.meshing.runner`) when the run meshes the structure.

Shape of a case file::

    [run]
    end_time = 2e-3            # s
    output_interval = 1e-4     # s between result frames
    time_step = 0.0            # s; 0 or absent = automatic (Silling & Askari estimate x safety_factor)
    safety_factor = 0.8        # applied to the automatic step
    pd_loop = "pairs"          # or "full_family" (the per-particle reference loop)
    gravity = [0, 0, 0]        # m/s^2
    short_range_contact = false  # repulsion between ice particles closer than 0.9 of their
                               # initial distance (fragments meeting again, floes meeting)
    allow_unstable_time_step = false  # a time_step above the stable estimate is an error
                               # (exit 2) unless this is true (then only a warning)
    checkpoint_interval_steps = 0      # write <out>/checkpoint.h5 every N coupling steps (0 = off)
    checkpoint_interval_minutes = 30.0 # ... and every M minutes of wall time (0 = off)
    stability_check_interval_steps = 10  # coupling steps between blow-up checks (speed, NaN,
                               # energy balance)
    energy_tolerance = 0.01    # energy the run may create, fraction of the energy supplied;
                               # more stops the run (exit 3) with the energy budget
    output_per_rank = false    # MPI: each rank writes its ice particles to results.rank<R>.h5

    [[ice]]
    name = "beam"
    dx = 0.01                  # m, lattice spacing
    horizon_factor = 3.015     # horizon = horizon_factor * dx (or give horizon = ... in m)
    shape = { box = { min = [0, 0, 0], max = [0.6, 0.1, 0.1] } }
    material = { density = 900, youngs_modulus = 4.1e9, poisson_ratio = 0.3, fracture_energy = 10 }
    initial_velocity = [0, 0, 0]
    fixed = [ { box = { min = [...], max = [...] } } ]
    prescribed_velocity = [ { region = { box = {...} }, velocity = [0, 0, -0.5], ramp_time = 1e-4 } ]
    no_fail = [ { box = {...} } ]
    cracks = [ { point = [0.3, 0.05, 0], normal = [1, 0, 0], box = { min = [...], max = [...] } } ]

    [[structure]]              # an elastic FE structure (or kind = "rigid")
    name = "panel"
    kind = "elastic"
    mesh = "hull_panel"        # a model of models/, a .py model file, or a .msh file
    params = { element_size = 0.08 }                  # model parameters (SI), models only
    material = { density = 7850, youngs_modulus = 210e9, poisson_ratio = 0.3 }
    fixed_groups = ["fixed"]
    contact_group = "contact"
    damping = { alpha = 0.0, beta = 0.0 }             # Rayleigh: alpha (1/s), beta (s)
    loads = [ { group = "contact", pressure = 1e5, pulse = { start = 0, rise = 1e-3, hold = 2e-3, fall = 1e-3 } } ]
    # kind = "rigid": motion = { velocity = [..] (m/s), angular_velocity = [..] (rad/s), center = [..] (m) }

    [[contact]]                # which ice body meets which structure (default: every pair)
    ice = "sheet"
    structure = "panel"
    name = "sheet-panel"       # default "<ice>-<structure>"
    friction = 0.0             # Coulomb coefficient
    search_radius = 0.0        # m; 0 = half the ice spacing dx

    [[monitor]]                # a probe recorded at every coupling step
    name = "mid"
    structure = "panel"
    point = [1.0, 0.6, 0.0]    # m; the nearest node (u) and element centre (von_mises)

Checkpoints hold the whole state (ice, structures, contact, clock, output counters); continue
a run with ``pdfem run CASE --restart <out>/checkpoint.h5``, which appends to the same results
file. A run whose state blows up (NaN/Inf, a particle moving more than a horizon in one step,
energy created beyond ``run.energy_tolerance`` of the energy supplied) stops with exit 3
and a diagnosis (:mod:`pdfem.run.blowup`).

The coupling step is the larger of the ice and structure stable steps; the faster side takes
``run.substeps`` steps per coupling step (0 or absent = chosen automatically).

Shapes and regions are one of ``box = {min, max}``, ``cylinder = {base, axis, radius, length}``,
``sphere = {center, radius}`` or (shapes only) ``mesh = {file, group}`` for a closed surface mesh
(path relative to the case file).
"""

from __future__ import annotations

from typing import Any

from pdfem.case.casefile import CaseFile
from pdfem.case.config import (Case, ContactConfig, Crack, IceConfig, MonitorConfig, Pulse, RunConfig,
                               StructureConfig, SurfaceLoad, VelocityBC)
from pdfem.case.loader import load_case, parse_case

__all__ = ["Case", "CaseFile", "ContactConfig", "Crack", "IceConfig", "MonitorConfig", "Pulse",
           "RunConfig", "StructureConfig", "SurfaceLoad", "VelocityBC", "json_schema", "load_case",
           "parse_case"]

#: Where the schema says it is from (``$id`` is not set: the file is written next to the cases).
SCHEMA_DIALECT = "https://json-schema.org/draft/2020-12/schema"


def json_schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of a case file: titles, descriptions with units and
    defaults, bounds, and ``additionalProperties: false`` everywhere (unknown keys are errors)."""
    schema = CaseFile.model_json_schema(by_alias=True)
    return {"$schema": SCHEMA_DIALECT, **schema}
