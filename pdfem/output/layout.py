"""Layout of a results file: where each quantity lives, which names are allowed, the histories.

Writer (:mod:`pdfem.output.writer`) and reader (:mod:`pdfem.output.reader`) share these names.
Layout of ``<stem>.h5`` (all quantities SI)::

    /meta                    attrs: version (pdfem version), units = "SI", case (TOML text),
                             created (ISO 8601 time), plus the writer's ``meta`` items
    /time                    (F,)      output time of each frame, s
    /ice/<body>/x0           (N, 3)    reference particle positions, m
    /ice/<body>/volume       (N,)      particle volumes, m^3 (if given)
    /ice/<body>/index        (N,)      int64 global particle numbers (per-rank files only)
    /ice/<body>/u            (F, N, 3) displacement, m
    /ice/<body>/v            (F, N, 3) velocity, m/s
    /ice/<body>/damage       (F, N)    broken fraction of the initial bonds, dimensionless
    /ice/<body>/x            (F, N, 3) positions, x0 + u, m (the writer records them; the
                             XDMF file draws the particles there)
    /ice/<body>/<field>      (F, N) or (F, N, 3)  any further per-particle field, e.g. theta
    /structure/<name>/points (Nn, 3)   reference node positions, m
    /structure/<name>/cells  (Ne, k)   int32 connectivity (VTK node order); attr cell_type
                             ("tetra", "hexahedron", "triangle" or "quad")
    /structure/<name>/u      (F, Nn, 3) nodal displacement, m
    /structure/<name>/x      (F, Nn, 3) node positions, points + u, m (recorded by the writer)
    /structure/<name>/von_mises (F, Ne) element von Mises stress, Pa (elastic structures)
    /structure/<name>/<field> (F, Nn or Ne) or (F, Nn or Ne, 3)  any further node or cell field
    /structure/<name>.contact/...  a structure's contact surface (triangles, u) with the cell
                             fields contact_pressure, contact_pressure_max (F, T) in Pa
                             (:mod:`pdfem.coupling.facet_loads`)
    /<history>/time          (K,)      e.g. /energy/time, /loads/<name>/time: step times, s
    /<history>/<key>         (K,) or (K, 3)  e.g. /energy/kinetic in J, /loads/<name>/force in N,
                             /loads/<name>/moment in N m, /loads/<name>.<patch>/force in N
    /xdmf/...                per-frame views for the XDMF file (:mod:`pdfem.output.xdmf`) and
                             the NaN a grid shows for a field its body has not
                             (:mod:`pdfem.output.xdmf_grids`), no data of their own

Frame fields are float64, chunked by up to 64 frames (about 256 KiB a chunk) and resizable
along the frame axis (:mod:`pdfem.output.frames`). Histories are float64, chunked by ``HISTORY_BLOCK`` rows and
written in blocks (:mod:`pdfem.output.histories`). Groups carry an attribute ``kind``
("ice_body", "structure" or "history") so readers can find them.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from datetime import datetime, timezone
from typing import Any

import h5py
import numpy as np

import pdfem

REQUIRED_ICE_FIELDS = ("u", "v", "damage")
"""Fields every ice body must give in every frame."""

REQUIRED_STRUCTURE_FIELDS = ("u",)
"""Fields every structure must give in every frame."""

POSITIONS = "x"
"""The per-frame field the writer records itself for every body: the positions at the frame,
reference + ``u`` (m), which the XDMF file draws the body at."""

CELL_FIELDS = frozenset({"von_mises", "contact_pressure", "contact_pressure_max"})
"""Structure fields centred on the cells (elements); all others are nodal."""

CONSTANT_DATASETS = frozenset({"x0", "volume", "index", "points", "cells"})
"""Datasets of a body without a frame axis (its reference configuration)."""

RESERVED = frozenset({"meta", "time", "ice", "structure", "xdmf"})
"""Top-level names that are not histories."""

_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.+\-]*\Z")


def check_name(name: str, what: str) -> str:
    """Return ``name`` if it is a plain HDF5 link name (letters, digits, ``_ . + -``).

    Parameters
    ----------
    name
        A body, field, history or key name.
    what
        What the name is, for the message, e.g. ``"field"``.

    Raises
    ------
    ValueError
        If the name has other characters or starts with ``.``, ``+`` or ``-``.
    """
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(
            f"{what} {name!r} is not a valid name: use letters, digits, '_', '.', '+', '-' "
            "and start with a letter, digit or '_'"
        )
    return name


def attr_value(v: Any) -> Any:
    """An HDF5 attribute value as plain Python: bytes decoded, numpy scalars unwrapped."""
    if isinstance(v, bytes):
        return v.decode()
    if isinstance(v, np.generic):
        return v.item()
    return v


def history_groups(file: h5py.File) -> list[tuple[str, h5py.Group]]:
    """Every history group of a results file (``kind = "history"``), with its name.

    Parameters
    ----------
    file
        An open results file.

    Returns
    -------
    list of (str, h5py.Group)
        ``(name, group)`` with names such as ``"energy"`` or ``"loads/panel"``; history groups
        are not searched for nested groups.
    """
    found = []
    stack = [(k, g) for k, g in file.items() if k not in RESERVED and isinstance(g, h5py.Group)]
    while stack:
        name, g = stack.pop()
        if attr_value(g.attrs.get("kind")) == "history":
            found.append((name, g))
        else:
            stack.extend((f"{name}/{k}", s) for k, s in g.items() if isinstance(s, h5py.Group))
    return found


def write_meta(file: h5py.File, case_text: str, meta: Mapping[str, Any]) -> None:
    """Create ``/meta``: pdfem version, units "SI", the case text, the time now, and ``meta``.

    Raises
    ------
    TypeError
        If a ``meta`` item cannot be stored as an HDF5 attribute.
    """
    m = file.create_group("meta")
    m.attrs["version"] = pdfem.__version__
    m.attrs["units"] = "SI"
    m.attrs["case"] = case_text
    m.attrs["created"] = datetime.now(timezone.utc).isoformat(timespec="seconds")
    for k, v in meta.items():
        try:
            m.attrs[k] = v
        except (TypeError, ValueError) as err:
            raise TypeError(f"meta item {k!r} = {v!r} cannot be stored as an HDF5 attribute "
                            "(use a string, a number or an array)") from err
