"""Case files: TOML text parsed into typed, validated objects.

A case file describes one run in SI units (m, kg, s, Pa, J/m^2). Every field is checked here,
once, before anything is built; an invalid or unknown field raises :class:`pdfem.errors.InputError`
naming the file, the field, the value and what would be valid. Case files are data: nothing in
them is evaluated.

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
    stability_check_interval_steps = 10  # coupling steps between blow-up checks (speed, NaN)
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
    point = [1.0, 0.6, 0.0]    # m; the nearest node (u) and the element containing it (von_mises)

Checkpoints hold the whole state (ice, structures, contact, clock, output counters); continue
a run with ``pdfem run CASE --restart <out>/checkpoint.h5``, which appends to the same results
file. A run whose state blows up (NaN/Inf, a particle moving more than a horizon in one step,
energy growing without work input) stops with exit 3 and a diagnosis (:mod:`pdfem.run.blowup`).

The coupling step is the larger of the ice and structure stable steps; the faster side takes
``run.substeps`` steps per coupling step (0 or absent = chosen automatically).

Shapes and regions are one of ``box = {min, max}``, ``cylinder = {base, axis, radius, length}``,
``sphere = {center, radius}`` or (shapes only) ``mesh = {file, group}`` for a closed surface mesh
(path relative to the case file).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pdfem.errors import InputError
from pdfem.pd.materials.lps import SEA_ICE_DEFAULTS, IceMaterial
from pdfem.geometry.shapes import Box, ClosedSurface, Cylinder, Sphere

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

Shape = Box | Cylinder | Sphere | ClosedSurface


class Table:
    """A TOML table being read: typed getters that record which keys were used.

    Every getter raises :class:`InputError` with the file and dotted field path; :meth:`done`
    rejects keys that no getter asked for (a misspelt key must not be silently ignored).
    """

    def __init__(self, data: Any, file: str, path: str):
        if not isinstance(data, dict):
            raise InputError(file, path or None, "expected a table ({ key = value, ... })", data)
        self.data, self.file, self.path = data, file, path
        self.used: set[str] = set()

    def field(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def error(self, key: str, message: str, value: Any = ...) -> InputError:
        return InputError(self.file, self.field(key), message, value)

    def has(self, key: str) -> bool:
        return key in self.data

    def raw(self, key: str, default: Any = ...) -> Any:
        self.used.add(key)
        if key not in self.data:
            if default is ...:
                raise self.error(key, "this field is required")
            return default
        return self.data[key]

    def number(self, key: str, default: Any = ..., *, low: float | None = None,
               high: float | None = None, low_open: bool = False, high_open: bool = False,
               unit: str = "") -> float:
        v = self.raw(key, default)
        if v is None:
            return None
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise self.error(key, f"expected a finite number{' in ' + unit if unit else ''}", v)
        bad = (low is not None and (v <= low if low_open else v < low)) or \
              (high is not None and (v >= high if high_open else v > high))
        if bad:
            lo = "" if low is None else (f"> {low:g}" if low_open else f">= {low:g}")
            hi = "" if high is None else (f"< {high:g}" if high_open else f"<= {high:g}")
            rng = " and ".join(s for s in (lo, hi) if s)
            raise self.error(key, f"must be {rng}{' ' + unit if unit else ''}", v)
        return float(v)

    def positive(self, key: str, default: Any = ..., unit: str = "") -> float:
        return self.number(key, default, low=0.0, low_open=True, unit=unit)

    def vector(self, key: str, default: Any = ..., unit: str = "") -> tuple[float, float, float]:
        v = self.raw(key, default)
        ok = isinstance(v, (list, tuple)) and len(v) == 3 and all(
            isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c) for c in v)
        if not ok:
            raise self.error(key, f"expected three finite numbers [x, y, z]{' in ' + unit if unit else ''}", v)
        return (float(v[0]), float(v[1]), float(v[2]))

    def string(self, key: str, default: Any = ..., choices: tuple[str, ...] | None = None) -> str:
        v = self.raw(key, default)
        if not isinstance(v, str) or not v:
            raise self.error(key, "expected a non-empty string", v)
        if choices and v not in choices:
            raise self.error(key, "must be one of " + ", ".join(f'"{c}"' for c in choices), v)
        return v

    def table(self, key: str, default: Any = ...) -> "Table":
        v = self.raw(key, default)
        return Table(v, self.file, self.field(key))

    def tables(self, key: str) -> list["Table"]:
        v = self.raw(key, [])
        if isinstance(v, dict):
            v = [v]
        if not isinstance(v, list):
            raise self.error(key, "expected a list of tables", v)
        return [Table(item, self.file, f"{self.field(key)}[{i}]") for i, item in enumerate(v)]

    def done(self) -> None:
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            known = ", ".join(sorted(self.used)) or "(none)"
            raise self.error(unknown[0], f"unknown key; the keys read here are: {known}")


@dataclass(frozen=True)
class RunConfig:
    """Time-loop settings (seconds)."""

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
    """One peridynamic ice body."""

    name: str
    dx: float
    horizon: float
    shape: Shape
    material: IceMaterial
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


def _shape(t: Table, base_dir: Path, allow_mesh: bool) -> Shape:
    kinds = ("box", "cylinder", "sphere") + (("mesh",) if allow_mesh else ())
    given = [k for k in kinds if t.has(k)]
    if len(given) != 1:
        extra = sorted(set(t.data) - set(kinds))
        what = f"unknown key '{extra[0]}'; " if extra else ""
        raise InputError(t.file, t.path, what + "expected exactly one of " + ", ".join(kinds), t.data)
    kind = given[0]
    s = t.table(kind)
    try:
        if kind == "box":
            shape = Box(s.vector("min", unit="m"), s.vector("max", unit="m"))
        elif kind == "cylinder":
            shape = Cylinder(s.vector("base", unit="m"), s.vector("axis"), s.positive("radius", unit="m"),
                             s.positive("length", unit="m"))
        elif kind == "sphere":
            shape = Sphere(s.vector("center", unit="m"), s.positive("radius", unit="m"))
        else:
            fname = s.string("file")
            group = s.string("group", None) if s.has("group") else None
            path = (base_dir / fname) if not Path(fname).is_absolute() else Path(fname)
            if not path.is_file():
                raise s.error("file", f"no such mesh file ({path})", fname)
            shape = ClosedSurface.from_file(path, group)
    except ValueError as exc:
        raise InputError(t.file, t.field(kind), str(exc)) from None
    s.done()
    t.done()
    return shape


def _material(t: Table) -> IceMaterial:
    d = SEA_ICE_DEFAULTS
    rho = t.positive("density", d["density"], unit="kg/m^3")
    E = t.positive("youngs_modulus", d["youngs_modulus"], unit="Pa")
    nu = t.number("poisson_ratio", d["poisson_ratio"], low=-1.0, high=0.5, low_open=True, high_open=True)
    if t.has("fracture_energy") and t.has("critical_stretch"):
        raise t.error("critical_stretch", "give either fracture_energy (J/m^2) or critical_stretch, not both")
    g0 = t.positive("fracture_energy", None if t.has("critical_stretch") else d["fracture_energy"], unit="J/m^2")
    s0 = t.positive("critical_stretch", None)
    t.done()
    return IceMaterial(density=rho, youngs_modulus=E, poisson_ratio=nu, fracture_energy=g0, critical_stretch=s0)


def _ice(t: Table, base_dir: Path) -> IceConfig:
    name = t.string("name")
    dx = t.positive("dx", unit="m")
    if t.has("horizon") and t.has("horizon_factor"):
        raise t.error("horizon", "give either horizon (m) or horizon_factor (multiple of dx), not both")
    if t.has("horizon"):
        horizon = t.positive("horizon", unit="m")
    else:
        horizon = t.number("horizon_factor", 3.015, low=1.0, low_open=True) * dx
    if horizon <= dx:
        raise t.error("horizon", f"the horizon must be larger than the spacing dx = {dx:g} m "
                      "(3 dx is usual: horizon_factor = 3.015)", horizon)
    shape = _shape(t.table("shape"), base_dir, allow_mesh=True)
    lo, hi = shape.bounds()
    if min(hi[k] - lo[k] for k in range(3)) < dx * (1 - 1e-9):
        raise t.error("dx", f"the spacing is larger than the body's thinnest extent "
                      f"({min(hi[k] - lo[k] for k in range(3)):g} m); choose a smaller dx", dx)
    material = _material(t.table("material", {}))
    v0 = t.vector("initial_velocity", (0.0, 0.0, 0.0), unit="m/s")
    fixed = tuple((_shape(r, base_dir, False), r.path) for r in t.tables("fixed"))
    no_fail = tuple((_shape(r, base_dir, False), r.path) for r in t.tables("no_fail"))
    bcs = []
    for r in t.tables("prescribed_velocity"):
        region = _shape(r.table("region"), base_dir, False)
        bcs.append(VelocityBC(region, r.vector("velocity", unit="m/s"),
                              r.number("ramp_time", 0.0, low=0.0, unit="s"), r.path))
        r.done()
    cracks = []
    for r in t.tables("cracks"):
        point = r.vector("point", unit="m")
        normal = r.vector("normal")
        if math.hypot(*normal) == 0.0:
            raise r.error("normal", "the crack plane's normal must not be zero", list(normal))
        b = r.table("box")
        try:
            box = Box(b.vector("min", unit="m"), b.vector("max", unit="m"))
        except ValueError as exc:
            raise InputError(b.file, b.path, str(exc)) from None
        b.done()
        r.done()
        cracks.append(Crack(point, normal, box, r.path))
    t.done()
    return IceConfig(name, dx, horizon, shape, material, v0, fixed, tuple(bcs), no_fail,
                     tuple(cracks), t.path)


def _strings(t: Table, key: str, default: tuple = ()) -> tuple[str, ...]:
    v = t.raw(key, list(default))
    if isinstance(v, str):
        v = [v]
    if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
        raise t.error(key, "expected a list of group names", v)
    return tuple(v)


def _is_gmsh(path: Path) -> bool:
    """Whether ``path`` starts like a gmsh .msh file (ASCII or binary: ``$MeshFormat``)."""
    try:
        with open(path, "rb") as fh:
            return fh.read(64).lstrip().startswith(b"$MeshFormat")
    except OSError:
        return False


def _structure(t: Table, base_dir: Path) -> StructureConfig:
    name = t.string("name")
    kind = t.string("kind", "elastic", choices=("elastic", "rigid"))
    mesh = t.string("mesh")
    if mesh.endswith((".msh", ".py")):
        path = Path(mesh) if Path(mesh).is_absolute() else base_dir / mesh
        if not path.is_file():
            raise t.error("mesh", f"no such file ({path}); give a .msh file, a .py model file, "
                          "or the name of a model in models/", mesh)
        if mesh.endswith(".msh") and not _is_gmsh(path):
            raise t.error("mesh", f"{path} is not a gmsh mesh file (it does not start with "
                          "$MeshFormat); write it from gmsh as .msh (format 4.1 or 2.2)", mesh)
        mesh = str(path)
    params = t.raw("params", {})
    if not isinstance(params, dict):
        raise t.error("params", "expected a table of model parameters", params)
    if params and mesh.endswith(".msh"):
        raise t.error("params", "model parameters apply to a model (name or .py), not to a .msh file")
    mat = t.table("material", {})
    rho = mat.positive("density", 7850.0, unit="kg/m^3")
    E = mat.positive("youngs_modulus", 210e9, unit="Pa")
    nu = mat.number("poisson_ratio", 0.3, low=-1.0, high=0.5, low_open=True, high_open=True)
    mat.done()
    fixed = _strings(t, "fixed_groups")
    contact = t.string("contact_group", "contact")
    damp = t.table("damping", {})
    alpha = damp.number("alpha", 0.0, low=0.0, unit="1/s")
    beta = damp.number("beta", 0.0, low=0.0, unit="s")
    damp.done()
    loads = []
    for r in t.tables("loads"):
        group = r.string("group")
        pressure = r.number("pressure", 0.0, unit="Pa")
        traction = r.vector("traction", (0.0, 0.0, 0.0), unit="Pa")
        pt = r.table("pulse", {})
        pulse = Pulse(pt.number("start", 0.0, low=0.0, unit="s"), pt.number("rise", 0.0, low=0.0, unit="s"),
                      pt.number("hold", math.inf, low=0.0, unit="s") if pt.has("hold") else math.inf,
                      pt.number("fall", 0.0, low=0.0, unit="s"))
        pt.done()
        r.done()
        loads.append(SurfaceLoad(group, pressure, traction, pulse, r.path))
    motion = t.table("motion", {}) if kind == "rigid" else None
    if motion is not None:
        vel = motion.vector("velocity", (0.0, 0.0, 0.0), unit="m/s")
        omega = motion.vector("angular_velocity", (0.0, 0.0, 0.0), unit="rad/s")
        center = motion.vector("center", (0.0, 0.0, 0.0), unit="m")
        motion.done()
        if fixed or loads:
            raise t.error("fixed_groups" if fixed else "loads",
                          "a rigid structure moves as prescribed by 'motion'; it takes no supports or loads")
    else:
        vel = omega = center = (0.0, 0.0, 0.0)
    t.done()
    return StructureConfig(name, kind, mesh, dict(params), rho, E, nu, fixed, contact, alpha, beta,
                           tuple(loads), vel, omega, center, t.path)


def _run(t: Table) -> RunConfig:
    end = t.positive("end_time", unit="s")
    out = t.positive("output_interval", end / 20, unit="s")
    if out > end:
        raise t.error("output_interval", f"longer than the run (end_time = {end:g} s); "
                      "choose an interval <= end_time", out)
    dt = t.number("time_step", 0.0, low=0.0, unit="s") or None
    sf = t.number("safety_factor", 0.8, low=0.0, high=1.0, low_open=True)
    loop = t.string("pd_loop", "pairs", choices=("pairs", "full_family"))
    g = t.vector("gravity", (0.0, 0.0, 0.0), unit="m/s^2")
    title = t.raw("title", "")
    if not isinstance(title, str):
        raise t.error("title", "expected a string", title)
    sub = t.raw("substeps", 0)
    if isinstance(sub, bool) or not isinstance(sub, int) or sub < 0:
        raise t.error("substeps", "expected a whole number >= 0 (0 = automatic)", sub)
    short = _boolean(t, "short_range_contact")
    unstable = _boolean(t, "allow_unstable_time_step")
    every = _whole(t, "checkpoint_interval_steps", 0, 0, "(0 = no step-based checkpoints)")
    minutes = t.number("checkpoint_interval_minutes", 30.0, low=0.0, unit="minutes")
    check = _whole(t, "stability_check_interval_steps", 10, 1, "")
    per_rank = _boolean(t, "output_per_rank")
    t.done()
    return RunConfig(end, out, dt, sf, loop, g, title, sub, short, unstable, every, minutes, check,
                     per_rank)


def _boolean(t: Table, key: str, default: bool = False) -> bool:
    v = t.raw(key, default)
    if not isinstance(v, bool):
        raise t.error(key, "expected true or false", v)
    return v


def _whole(t: Table, key: str, default: int, low: int, note: str) -> int:
    v = t.raw(key, default)
    if isinstance(v, bool) or not isinstance(v, int) or v < low:
        raise t.error(key, f"expected a whole number >= {low} {note}".rstrip(), v)
    return v


def _contacts(top: Table, ice: tuple[IceConfig, ...],
              structures: tuple[StructureConfig, ...]) -> tuple[ContactConfig, ...]:
    tables = top.tables("contact")
    if not tables:  # default: every ice body meets every structure
        return tuple(ContactConfig(f"{b.name}-{s.name}", b.name, s.name) for b in ice
                     for s in structures)
    ice_names = [b.name for b in ice]
    st_names = [s.name for s in structures]
    out: list[ContactConfig] = []
    for t in tables:
        b = t.string("ice")
        if b not in ice_names:
            raise t.error("ice", "no ice body of that name; the case has: "
                          + (", ".join(ice_names) or "(none)"), b)
        st = t.string("structure")
        if st not in st_names:
            raise t.error("structure", "no structure of that name; the case has: "
                          + (", ".join(st_names) or "(none)"), st)
        name = t.string("name", f"{b}-{st}")
        if any(c.name == name for c in out):
            raise t.error("name", "contact names must be unique", name)
        if any((c.ice, c.structure) == (b, st) for c in out):
            raise t.error("structure", f"ice '{b}' and structure '{st}' already have a contact")
        mu = t.number("friction", 0.0, low=0.0)
        r = t.number("search_radius", 0.0, low=0.0, unit="m")
        t.done()
        out.append(ContactConfig(name, b, st, mu, r, t.path))
    return tuple(out)


def _monitors(top: Table, structures: tuple[StructureConfig, ...]) -> tuple[MonitorConfig, ...]:
    names = [s.name for s in structures]
    out: list[MonitorConfig] = []
    for t in top.tables("monitor"):
        name = t.string("name")
        if any(m.name == name for m in out):
            raise t.error("name", "monitor names must be unique", name)
        st = t.string("structure")
        if st not in names:
            raise t.error("structure", "no structure of that name; the case has: "
                          + (", ".join(names) or "(none)"), st)
        if next(s for s in structures if s.name == st).kind != "elastic":
            raise t.error("structure", "monitors need an elastic structure", st)
        point = t.vector("point", unit="m")
        t.done()
        out.append(MonitorConfig(name, st, point, t.path))
    return tuple(out)


def parse_case(text: str, file: str = "<string>", directory: Path | None = None) -> Case:
    """Parse and validate a case from TOML text.

    Parameters
    ----------
    text
        The TOML source.
    file
        Name used in error messages.
    directory
        Directory that relative paths in the case (meshes) are resolved against.

    Returns
    -------
    Case
        The validated case.

    Raises
    ------
    InputError
        For malformed TOML, unknown keys, wrong types or out-of-range values.
    """
    directory = Path(directory) if directory is not None else Path.cwd()
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(file, None, f"not valid TOML: {exc}") from None
    top = Table(data, file, "")
    run = _run(top.table("run"))
    ice = tuple(_ice(t, directory) for t in top.tables("ice"))
    structures = tuple(_structure(t, directory) for t in top.tables("structure"))
    if not ice and not structures:
        raise top.error("ice", "a case needs at least one [[ice]] body or [[structure]]")
    names = [b.name for b in ice] + [s.name for s in structures]
    fields = [b.field for b in ice] + [s.field for s in structures]
    for i, n in enumerate(names):
        if n in names[:i]:
            raise InputError(file, f"{fields[i]}.name", "body and structure names must be unique", n)
    contacts = _contacts(top, ice, structures)
    monitors = _monitors(top, structures)
    top.done()
    return Case(run=run, ice=ice, structures=structures, contacts=contacts, monitors=monitors,
                file=file, text=text, directory=directory)


def load_case(path: str | Path) -> Case:
    """Read and validate a case file (see :func:`parse_case`)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(str(path), None, "no such case file")
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(str(path), None, f"cannot read the case file: {exc}") from None
    return parse_case(text, str(path), p.resolve().parent)
