"""The validated case as the builders in :mod:`pdfem.run` read it: plain frozen dataclasses in SI
units, with every default filled in (horizon in m, shapes as :mod:`pdfem.geometry.shapes`
objects, mesh paths resolved, one contact per ice-structure pair when none is given) and the
dotted field path of each entry (``field``) for error messages.

:func:`resolve` makes a :class:`Case` from a validated :class:`~pdfem.case.casefile.CaseFile`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from pdfem.case.casefile import CaseFile
from pdfem.case.ice import IceMaterialSection, IceSection
from pdfem.case.shapes import Shape
from pdfem.geometry.shapes import Box
from pdfem.case.structure import StructureSection


@dataclass(frozen=True)
class RunConfig:
    """Time-loop settings (seconds); see :class:`pdfem.case.run.RunSection`."""

    end_time: float
    output_interval: float
    time_step: float | None = None
    safety_factor: float = 0.8
    pd_loop: str = "pairs"
    gravity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    title: str = ""
    substeps: int = 0
    short_range_contact: bool = False
    allow_unstable_time_step: bool = False
    checkpoint_interval_steps: int = 0
    checkpoint_interval_minutes: float = 30.0
    stability_check_interval_steps: int = 10
    output_per_rank: bool = False


@dataclass(frozen=True)
class VelocityBC:
    """Particles in ``region`` move with ``velocity`` (m/s), ramped linearly over ``ramp_time`` (s)."""

    region: Shape
    velocity: tuple[float, float, float]
    ramp_time: float = 0.0
    field: str = ""


@dataclass(frozen=True)
class Crack:
    """A planar pre-crack: the part of the plane (``point``, ``normal``) inside ``box``.

    Every bond crossing it is broken at t = 0.
    """

    point: tuple[float, float, float]
    normal: tuple[float, float, float]
    box: Box
    field: str = ""


@dataclass(frozen=True)
class IceConfig:
    """One peridynamic ice body; ``material`` is the case's material section (SI)."""

    name: str
    dx: float
    horizon: float
    shape: Shape
    material: IceMaterialSection
    initial_velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    fixed: tuple[tuple[Shape, str], ...] = ()
    prescribed_velocity: tuple[VelocityBC, ...] = ()
    no_fail: tuple[tuple[Shape, str], ...] = ()
    cracks: tuple[Crack, ...] = ()
    field: str = ""


@dataclass(frozen=True)
class Pulse:
    """Trapezoidal time history (s): 0 before ``start``, rises linearly over ``rise`` to 1,
    holds for ``hold``, falls linearly over ``fall`` to 0. ``hold = inf`` keeps it on."""

    start: float = 0.0
    rise: float = 0.0
    hold: float = math.inf
    fall: float = 0.0

    def __call__(self, t: float) -> float:
        s = t - self.start
        if s < 0.0:
            return 0.0
        if s < self.rise:
            return s / self.rise
        s -= self.rise
        if s <= self.hold:
            return 1.0
        s -= self.hold
        if s < self.fall:
            return 1.0 - s / self.fall
        return 0.0


@dataclass(frozen=True)
class SurfaceLoad:
    """A uniform pressure (Pa, positive into the structure) and/or traction (Pa) on a group."""

    group: str
    pressure: float = 0.0
    traction: tuple[float, float, float] = (0.0, 0.0, 0.0)
    pulse: Pulse = Pulse()
    field: str = ""


@dataclass(frozen=True)
class StructureConfig:
    """One structure: an elastic FE model or a rigid body with prescribed motion."""

    name: str
    kind: str
    mesh: str
    params: dict = field(default_factory=dict)
    density: float = 7850.0
    youngs_modulus: float = 210e9
    poisson_ratio: float = 0.3
    fixed_groups: tuple[str, ...] = ()
    contact_group: str = "contact"
    damping_alpha: float = 0.0
    damping_beta: float = 0.0
    loads: tuple[SurfaceLoad, ...] = ()
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    angular_velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)
    field: str = ""


@dataclass(frozen=True)
class ContactConfig:
    """Contact between one ice body and one structure's contact surface."""

    name: str
    ice: str
    structure: str
    friction: float = 0.0
    search_radius: float = 0.0   # m; 0 = half the ice spacing
    field: str = ""


@dataclass(frozen=True)
class MonitorConfig:
    """A probe on a structure: displacement of the node nearest ``point`` and von Mises stress
    of the element containing it, recorded at every coupling step."""

    name: str
    structure: str
    point: tuple[float, float, float]
    field: str = ""


@dataclass(frozen=True)
class Case:
    """A validated case: what to simulate and how."""

    run: RunConfig
    ice: tuple[IceConfig, ...]
    structures: tuple[StructureConfig, ...] = ()
    contacts: tuple[ContactConfig, ...] = ()
    monitors: tuple[MonitorConfig, ...] = ()
    file: str = "<built-in>"
    text: str = ""
    directory: Path = field(default_factory=Path.cwd)


def _ice(s: IceSection, at: str) -> IceConfig:
    bcs = tuple(VelocityBC(r.region.geometry, r.velocity, r.ramp_time, f"{at}.prescribed_velocity[{k}]")
                for k, r in enumerate(s.prescribed_velocity))
    cracks = tuple(Crack(c.point, c.normal, c.box.build(), f"{at}.cracks[{k}]")
                   for k, c in enumerate(s.cracks))
    return IceConfig(s.name, s.dx, s.horizon_length(), s.shape.geometry, s.material,
                     s.initial_velocity,
                     tuple((r.geometry, f"{at}.fixed[{k}]") for k, r in enumerate(s.fixed)), bcs,
                     tuple((r.geometry, f"{at}.no_fail[{k}]") for k, r in enumerate(s.no_fail)),
                     cracks, at)


def _structure(s: StructureSection, at: str) -> StructureConfig:
    loads = []
    for k, r in enumerate(s.loads):
        p = r.pulse
        pulse = Pulse(p.start, p.rise, math.inf if p.hold is None else p.hold, p.fall)
        loads.append(SurfaceLoad(r.group, r.pressure, r.traction, pulse, f"{at}.loads[{k}]"))
    m = s.motion
    return StructureConfig(s.name, s.kind, s.mesh, dict(s.params), s.material.density,
                           s.material.youngs_modulus, s.material.poisson_ratio, s.fixed_groups,
                           s.contact_group, s.damping.alpha, s.damping.beta, tuple(loads),
                           m.velocity, m.angular_velocity, m.center, at)


def resolve(data: CaseFile, file: str, text: str, directory: Path) -> Case:
    """The :class:`Case` that a validated case file describes (defaults filled in)."""
    r = data.run
    run = RunConfig(r.end_time, r.end_time / 20 if r.output_interval is None else r.output_interval,
                    r.time_step or None, r.safety_factor, r.pd_loop, r.gravity, r.title, r.substeps,
                    r.short_range_contact, r.allow_unstable_time_step, r.checkpoint_interval_steps,
                    r.checkpoint_interval_minutes, r.stability_check_interval_steps,
                    r.output_per_rank)
    ice = tuple(_ice(s, f"ice[{k}]") for k, s in enumerate(data.ice))
    structures = tuple(_structure(s, f"structure[{k}]") for k, s in enumerate(data.structure))
    if data.contact:
        contacts = tuple(ContactConfig(c.name or f"{c.ice}-{c.structure}", c.ice, c.structure,
                                       c.friction, c.search_radius, f"contact[{k}]")
                         for k, c in enumerate(data.contact))
    else:  # default: every ice body meets every structure
        contacts = tuple(ContactConfig(f"{b.name}-{s.name}", b.name, s.name) for b in ice
                         for s in structures)
    monitors = tuple(MonitorConfig(m.name, m.structure, m.point, f"monitor[{k}]")
                     for k, m in enumerate(data.monitor))
    return Case(run=run, ice=ice, structures=structures, contacts=contacts, monitors=monitors,
                file=file, text=text, directory=directory)
