"""Output sources: what a component of a run writes to the results, and when.

A source (an ice body, a structure, a contact pair, a monitor, the energy balance) hands the
results writer its data at two moments:

* every output frame: fields on its mesh (:meth:`OutputSource.frame_fields`: per particle,
  node or cell, written under ``/ice/<name>`` or ``/structure/<name>``) and history rows
  (:meth:`OutputSource.frame_rows`);
* every coupling step: history rows (:meth:`OutputSource.step_rows`).

A history row is ``{group: {key: scalar or small array}}``, e.g. ``{"loads/panel": {"force":
(3,), "moment": (3,), "contacts": n}}``. Units are SI; :data:`UNITS` names the unit of each key
pdfem writes. The driver adapts sources to the writer's calls
(:class:`pdfem.output.writer.ResultsWriter`: ``write_frame`` and ``append_history``).

Adding a source
---------------
Write a class with the methods of :class:`OutputSource` (subclass :class:`Source` for empty
defaults) in the module of the component it reports on, or in :mod:`pdfem.run.outputs`, and
add one entry to :data:`pdfem.run.outputs.SOURCE_KINDS` (its ``of_run(setup, per_rank)``
makes the sources of a built run).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

Rows = dict[str, dict[str, Any]]
"""History rows: ``{history group: {key: value}}``."""

UNITS: dict[str, str] = {
    "u": "m", "v": "m/s", "damage": "1", "von_mises": "Pa",
    "force": "N", "moment": "N m", "contacts": "1", "applied": "N",
    "kinetic": "J", "kinetic_correction": "J", "strain": "J", "gravity_potential": "J",
    "external_work": "J",
    "structure_kinetic": "J", "structure_strain": "J", "short_range_potential": "J",
    "rigid_body_work": "J", "dissipated": "J", "contact_dissipated": "J",
    "fracture_dissipated": "J", "damping_dissipated": "J", "structure_kinetic_correction": "J",
    "load_work": "J", "support_work": "J", "supplied": "J", "stored": "J", "residual": "J",
    "reaction_<group>": "N", "area": "m^2", "contact_pressure": "Pa",
    "contact_pressure_max": "Pa", "water_potential": "J", "water_drag_dissipated": "J",
    "structure_potential": "J", "u_elastic": "m", "frame_angle": "rad", "drive_work": "J",
    "position": "m", "rotation": "rad", "velocity": "m/s", "angular_velocity": "rad/s",
    "hydrostatic_force": "N", "hydrostatic_moment": "N m",
    **{k: "N m" for k in ("ice_torque", "shaft_torque", "spindle_torque", "bending_out_of_plane",
                          "bending_in_plane")},  # shaft/<name>[.<blade>], pdfem.motion.shaft_loads
    "thrust": "N", "ice_force": "N", "force_blade": "N", "shaft_power": "W", "shaft_work": "J",
    "ice_work": "J", "energy_change": "J", "shaft_angular_impulse": "N m s",
    "ice_angular_impulse": "N m s", "angular_momentum_change": "kg m^2/s", "max_von_mises": "Pa",
    "max_von_mises_location": "m", "root_moment": "N m", "stress": "Pa",
    "attached_impulse": "N s", "attached_work": "J", "external_impulse": "N s",
}
"""Unit of each field or history key that pdfem writes."""


@runtime_checkable
class OutputSource(Protocol):
    """What a component writes: fields per frame, history rows per frame and per step."""

    name: str
    mesh_kind: str
    """``"ice"``, ``"structure"`` (fields on a mesh of that group) or ``""`` (histories only)."""

    def frame_fields(self) -> dict[str, np.ndarray] | None:
        """Fields of one output frame on the source's mesh (None: nothing on this rank)."""
        ...

    def frame_rows(self) -> Rows:
        """History rows written at every output frame."""
        ...

    def step_rows(self) -> Rows:
        """History rows written at every coupling step."""
        ...


class Source:
    """An :class:`OutputSource` that writes nothing; subclasses override what they write."""

    name: str = ""
    mesh_kind: str = ""

    def frame_fields(self) -> dict[str, np.ndarray] | None:
        """No fields."""
        return None

    def frame_rows(self) -> Rows:
        """No rows."""
        return {}

    def step_rows(self) -> Rows:
        """No rows."""
        return {}
