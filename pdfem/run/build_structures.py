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
from pdfem.fem.base import Structure
from pdfem.fem.elasticity import ElasticMaterial
from pdfem.fem.moving_frame import MovingFrame
from pdfem.fem.rigid import RigidBody
from pdfem.fem.ship import Ship
from pdfem.geometry.path import DisplacementPath
from pdfem.fem.rotating import FrameStructure
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


def _elastic(cfg: StructureConfig, path: Path, file: str) -> ElasticStructure:
    """An elastic FE structure of the case's element order with its supports (clamped and per
    component), damping and surface loads; solved in its moving frame if it has a motion."""
    material = ElasticMaterial(cfg.density, cfg.youngs_modulus, cfg.poisson_ratio)
    frame = MovingFrame(cfg.angular_velocity, cfg.center, cfg.velocity, cfg.ramp_time)
    kind, extra = (ElasticStructure, {}) if frame.is_still else (FrameStructure, {"frame": frame})
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


def build_structure(cfg: StructureConfig, out_dir: Path, file: str = "<case>",
                    remesh: bool = True) -> Structure:
    """Build the structure that ``cfg`` describes with the builder of its kind
    (:data:`STRUCTURE_KINDS`; ``remesh``: see :func:`structure_mesh`).

    Raises
    ------
    InputError
        For a mesh or group the structure cannot be built from.
    """
    path = structure_mesh(cfg, out_dir, file, remesh)
    check_groups(cfg, path, file)
    try:
        return STRUCTURE_KINDS[cfg.kind](cfg, path, file)
    except InputError:
        raise
    except (ValueError, OSError) as exc:
        raise InputError(file, f"{cfg.field}.mesh", f"{exc} (mesh file {path})") from None
