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
from pdfem.case.links import ContactSection
from pdfem.case.ice import IceMaterialSection, IceSection
from pdfem.case.shapes import Shape
from pdfem.geometry.shapes import Box
from pdfem.case.structure import ShipConfig, StructureSection, ship_config
from pdfem.case.water import WaterSection, gravity_with_water


@dataclass(frozen=True)
class RunConfig:
    """Time-loop settings (seconds); see :class:`pdfem.case.run.RunSection`.

    The dataclasses here have no defaults of their own: every default is declared once, in the
    schema's sections, and :func:`resolve` passes every value."""

    end_time: float
    output_interval: float
    time_step: float | None
    safety_factor: float
    pd_loop: str
    gravity: tuple[float, float, float]
    title: str
    substeps: int
    short_range_contact: bool
    allow_unstable_time_step: bool
    checkpoint_interval_steps: int
    checkpoint_interval_minutes: float
    stability_check_interval_steps: int
    energy_tolerance: float
    output_per_rank: bool
    rebalance_every: int
    rebalance_imbalance: float


@dataclass(frozen=True)
class VelocityBC:
    """Particles in ``region`` move with ``velocity`` (m/s), ramped linearly over ``ramp_time``
    (s), or follow the displacement ``path`` (rows ``(t, ux, uy, uz)``, s and m; ``velocity`` is
    then zero); ``name`` names the reaction history ``loads/<body>.<name>``."""

    region: Shape
    velocity: tuple[float, float, float]
    ramp_time: float
    path: tuple[tuple[float, float, float, float], ...] | None
    name: str
    field: str = ""


@dataclass(frozen=True)
class FixedRegion:
    """Particles in ``region`` are held in place; ``name`` names the reaction history."""

    region: Shape
    name: str
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
    initial_velocity: tuple[float, float, float]
    fixed: tuple[FixedRegion, ...]
    prescribed_velocity: tuple[VelocityBC, ...]
    no_fail: tuple[tuple[Shape, str], ...]
    cracks: tuple[Crack, ...]
    field: str = ""


@dataclass(frozen=True)
class Pulse:
    """Trapezoidal time history (s): 0 before ``start``, rises linearly over ``rise`` to 1,
    holds for ``hold``, falls linearly over ``fall`` to 0. ``hold = inf`` keeps it on."""

    start: float
    rise: float
    hold: float
    fall: float

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
    pressure: float
    traction: tuple[float, float, float]
    pulse: Pulse
    field: str = ""


@dataclass(frozen=True)
class StructureConfig:
    """One structure: an elastic FE model or a rigid body with prescribed motion."""

    name: str
    kind: str
    mesh: str
    params: dict
    density: float
    youngs_modulus: float
    poisson_ratio: float
    fixed_groups: tuple[str, ...]
    supports: tuple[tuple[str, tuple[str, ...]], ...]
    element_order: int
    contact_group: str
    damping_alpha: float
    damping_beta: float
    loads: tuple[SurfaceLoad, ...]
    velocity: tuple[float, float, float]
    angular_velocity: tuple[float, float, float]
    center: tuple[float, float, float]
    path: tuple[tuple[float, float, float, float], ...] | None
    field: str = ""
    ship: ShipConfig | None = None  # kind = "ship" only
    ramp_time: float = 0.0          # s, the elastic structure's moving frame
    attached_to: str | None = None  # the ship an elastic structure rides on
    integrator: str = "explicit"    # elastic structures: "explicit" or "implicit"


@dataclass(frozen=True)
class ContactConfig:
    """Contact between one ice body and one structure's contact surface."""

    name: str
    ice: str
    structure: str
    friction: float
    search_radius: float
    field: str = ""


@dataclass(frozen=True)
class MonitorConfig:
    """A probe on a structure: displacement of the node nearest ``point`` and von Mises stress
    of the element whose centre is nearest, recorded at every coupling step."""

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
    water: WaterSection | None = None  # [water] section, None: no water
    file: str = "<built-in>"
    text: str = ""
    directory: Path = field(default_factory=Path.cwd)


def _ice(s: IceSection, at: str) -> IceConfig:
    fixed_names, driven_names = s.region_names()
    bcs = tuple(VelocityBC(region=r.region.geometry, velocity=r.velocity or (0.0, 0.0, 0.0),
                           ramp_time=r.ramp_time, path=r.path, name=driven_names[k],
                           field=f"{at}.prescribed_velocity[{k}]")
                for k, r in enumerate(s.prescribed_velocity))
    cracks = tuple(Crack(point=c.point, normal=c.normal, box=c.box.build(),
                         field=f"{at}.cracks[{k}]")
                   for k, c in enumerate(s.cracks))
    return IceConfig(
        name=s.name, dx=s.dx, horizon=s.horizon_length(), shape=s.shape.geometry,
        material=s.material, initial_velocity=s.initial_velocity,
        fixed=tuple(FixedRegion(r.geometry, fixed_names[k], f"{at}.fixed[{k}]")
                    for k, r in enumerate(s.fixed)),
        prescribed_velocity=bcs,
        no_fail=tuple((r.geometry, f"{at}.no_fail[{k}]") for k, r in enumerate(s.no_fail)),
        cracks=cracks, field=at)


def _structure(s: StructureSection, at: str, water=None,
               gravity=(0.0, 0.0, -9.81)) -> StructureConfig:
    loads = []
    for k, r in enumerate(s.loads):
        p = r.pulse
        pulse = Pulse(start=p.start, rise=p.rise, hold=math.inf if p.hold is None else p.hold,
                      fall=p.fall)
        loads.append(SurfaceLoad(group=r.group, pressure=r.pressure, traction=r.traction,
                                 pulse=pulse, field=f"{at}.loads[{k}]"))
    m = s.motion
    return StructureConfig(
        name=s.name, kind=s.kind, mesh=s.mesh, params=dict(s.params), density=s.material.density,
        youngs_modulus=s.material.youngs_modulus, poisson_ratio=s.material.poisson_ratio,
        fixed_groups=s.fixed_groups,
        supports=tuple((r.group, tuple(r.components)) for r in s.supports),
        element_order=s.element_order, contact_group=s.contact_group,
        damping_alpha=s.damping.alpha, damping_beta=s.damping.beta, loads=tuple(loads),
        velocity=m.velocity, angular_velocity=m.angular_velocity, center=m.center, path=m.path,
        field=at, ship=ship_config(s, water, gravity), ramp_time=m.ramp_time,
        attached_to=s.attached_to, integrator=s.integrator)


def resolve(data: CaseFile, file: str, text: str, directory: Path) -> Case:
    """The :class:`Case` that a validated case file describes (defaults filled in)."""
    r = data.run
    run = RunConfig(
        end_time=r.end_time,
        output_interval=r.end_time / 20 if r.output_interval is None else r.output_interval,
        time_step=r.time_step or None, safety_factor=r.safety_factor, pd_loop=r.pd_loop,
        gravity=gravity_with_water(r.gravity, "gravity" in r.model_fields_set, data.water),
        title=r.title, substeps=r.substeps,
        short_range_contact=r.short_range_contact,
        allow_unstable_time_step=r.allow_unstable_time_step,
        checkpoint_interval_steps=r.checkpoint_interval_steps,
        checkpoint_interval_minutes=r.checkpoint_interval_minutes,
        stability_check_interval_steps=r.stability_check_interval_steps,
        energy_tolerance=r.energy_tolerance,
        output_per_rank=r.output_per_rank, rebalance_every=r.rebalance_every,
        rebalance_imbalance=r.rebalance_imbalance)
    ice = tuple(_ice(s, f"ice[{k}]") for k, s in enumerate(data.ice))
    structures = tuple(_structure(s, f"structure[{k}]", data.water, run.gravity)
                       for k, s in enumerate(data.structure))
    sections = data.contact or tuple(  # default: every ice body meets every structure
        ContactSection(ice=b.name, structure=s.name) for b in ice for s in structures)
    contacts = tuple(ContactConfig(name=c.name or f"{c.ice}-{c.structure}", ice=c.ice,
                                   structure=c.structure, friction=c.friction,
                                   search_radius=c.search_radius,
                                   field=f"contact[{k}]" if data.contact else "")
                     for k, c in enumerate(sections))
    monitors = tuple(MonitorConfig(name=m.name, structure=m.structure, point=m.point,
                                   field=f"monitor[{k}]")
                     for k, m in enumerate(data.monitor))
    return Case(run=run, ice=ice, structures=structures, contacts=contacts, monitors=monitors,
                water=data.water, file=file, text=text, directory=directory)
