"""Structures from validated case entries: mesh the model (or read the .msh), then build the
structure of the entry's kind (the registry :data:`STRUCTURE_KINDS`).

A model named in the case (a model of ``models/`` or a ``.py`` file) is meshed with gmsh into the
run's output directory, so the mesh used by a run is kept beside its results. Problems with the
mesh or its groups are user errors, reported with the case-file field.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from pdfem.case.schema import StructureConfig
from pdfem.errors import InputError
from pdfem.motion.attached_frame import AttachedStructure
from pdfem.fem.base import Structure
from pdfem.fem.elasticity import ElasticMaterial
from pdfem.motion.moving_frame import MovingFrame
from pdfem.motion.rigid import RigidBody
from pdfem.motion.ship import InertiaError, Ship
from pdfem.geometry.path import DisplacementPath
from pdfem.motion.frame_structure import FrameStructure
from pdfem.fem.structure import ElasticStructure
from pdfem.output.files import inside
from pdfem.run.mesh_groups import check_groups


def structure_mesh(cfg: StructureConfig, out_dir: Path, file: str = "<case>",
                   remesh: bool = True) -> Path:
    """The .msh file of a structure: the case's file, or its model meshed into ``out_dir``
    (``remesh=False``: the mesh already written there, e.g. by MPI rank 0)."""
    if cfg.mesh.endswith(".msh"):
        return Path(cfg.mesh)
    from pdfem.meshing.runner import mesh_model
    target = inside(out_dir, f"{cfg.name}.msh")
    if not remesh:
        return target
    try:
        mesh_model(cfg.mesh, {k: v for k, v in cfg.params.items()}, target)
    except InputError as exc:
        raise InputError(file, f"{cfg.field}.params.{exc.field}" if exc.field not in
                         (None, "model") else f"{cfg.field}.mesh", exc.message, exc.value) from None
    return target


def _rigid(cfg: StructureConfig, path: Path, file: str) -> RigidBody:
    """A rigid body with the case's prescribed motion (velocity or translation path), from its
    contact group's surface."""
    motion = None if cfg.path is None else DisplacementPath(cfg.path)
    return RigidBody.from_msh(path, cfg.contact_group, velocity=cfg.velocity,
                              angular_velocity=cfg.angular_velocity, centre=cfg.center,
                              name=cfg.name, translation=motion)


def _elastic(cfg: StructureConfig, path: Path, file: str, ship=None) -> ElasticStructure:
    """An elastic FE structure of the case's element order with its supports (clamped and per
    component), damping and surface loads; solved in its moving frame if it has a motion, or in
    the frame of the ship ``ship`` it is attached to."""
    material = ElasticMaterial(cfg.density, cfg.youngs_modulus, cfg.poisson_ratio)
    frame = MovingFrame(cfg.angular_velocity, cfg.center, cfg.velocity, cfg.ramp_time,
                        path=None if cfg.path is None else tuple(map(tuple, cfg.path)))
    kind, extra = ((ElasticStructure, {"integrator": cfg.integrator}) if frame.is_still
                   else (FrameStructure, {"frame": frame, "integrator": cfg.integrator}))
    if ship is not None:
        kind, extra = AttachedStructure, {"ship": ship}
    s = kind.from_file(path, material, fixed_groups=cfg.fixed_groups,
                       supports=dict(cfg.supports), element_order=cfg.element_order,
                       contact_group=cfg.contact_group, name=cfg.name,
                       rayleigh_alpha=cfg.damping_alpha, rayleigh_beta=cfg.damping_beta, **extra)
    for load in cfg.loads:
        try:
            s.add_surface_load(load.group, load.traction, load.pressure, history=load.pulse)
        except ValueError as exc:
            raise InputError(file, f"{load.field}.group", str(exc), load.group) from None
    return s


STRUCTURE_KINDS: dict[str, Callable[[StructureConfig, Path, str], Structure]] = {
    "elastic": _elastic,
    "rigid": _rigid,
    "ship": Ship.from_case,
}
"""The case's structure ``kind`` -> builder ``(config, mesh path, case file) -> Structure``.
A new kind: its :class:`~pdfem.fem.base.Structure` in a new file of :mod:`pdfem.fem` and one
line here (builder errors: :class:`ValueError` or :class:`OSError` for a bad mesh, or an
:class:`~pdfem.errors.InputError` naming the field)."""


def _ship_of(cfg: StructureConfig, ships: dict, file: str) -> Ship:
    """The ship an elastic structure is attached to, by name among the case's ships."""
    if cfg.attached_to not in ships:
        raise InputError(file, f"{cfg.field}.attached_to", "a structure rides on a ship "
                         "(kind = \"ship\") of the case; there is no ship of that name (the "
                         f"case's ships: {', '.join(ships) or 'none'})", cfg.attached_to)
    return ships[cfg.attached_to]


def build_structure(cfg: StructureConfig, out_dir: Path, file: str = "<case>",
                    remesh: bool = True, ships: dict | None = None) -> Structure:
    """Build the structure that ``cfg`` describes with the builder of its kind
    (:data:`STRUCTURE_KINDS`; ``remesh``: see :func:`structure_mesh`); ``ships``: the case's
    ships by name (the one a structure is ``attached_to``).

    Raises
    ------
    InputError
        For a mesh or group the structure cannot be built from, or a missing ship.
    """
    ship = None if cfg.attached_to is None else _ship_of(cfg, ships or {}, file)
    path = structure_mesh(cfg, out_dir, file, remesh)
    check_groups(cfg, path, file)
    try:
        if ship is not None:
            return _elastic(cfg, path, file, ship)
        return STRUCTURE_KINDS[cfg.kind](cfg, path, file)
    except InputError:
        raise
    except InertiaError as exc:   # the riders outweigh the ship (pdfem.motion.attached_step)
        raise InputError(file, f"{ship.field}.ship.{exc.key}", str(exc)) from None
    except (ValueError, OSError) as exc:
        raise InputError(file, f"{cfg.field}.mesh", f"{exc} (mesh file {path})") from None


def stepping_order(configs) -> list[int]:
    """Indices of the case's structures in the order they are stepped: case order, except that
    a structure listed before the ship it rides on (``attached_to``) comes right after it (in
    every (sub)step the ship must step first: :mod:`pdfem.motion.attached_frame`)."""
    order: list[int] = []
    for k, cfg in enumerate(configs):
        if cfg.attached_to is None or any(configs[q].name == cfg.attached_to for q in order):
            order.append(k)
        for q, other in enumerate(configs):  # riders listed before this ship follow it
            if q < k and other.attached_to == cfg.name and q not in order:
                order.append(q)
    return order


def build_all(configs, out_dir: Path, file: str = "<case>", remesh: bool = True) -> list:
    """The case's structures (:func:`build_structure`) in :func:`stepping_order`; a structure
    attached to a ship finds it by name wherever the case lists it."""
    built, ships = {}, {}
    free = [k for k, cfg in enumerate(configs) if cfg.attached_to is None]
    for k in free + [k for k in range(len(configs)) if k not in free]:
        built[k] = build_structure(configs[k], out_dir, file, remesh, ships)
        if configs[k].kind == "ship":
            ships[configs[k].name] = built[k]
    return [built[k] for k in stepping_order(configs)]
