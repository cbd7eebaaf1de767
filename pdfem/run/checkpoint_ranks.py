"""The ice and particle-force parts of a checkpoint: written by each rank, read by any rank count.

A *part* is what one rank holds: per ice body ``/ice/<body>`` its owned particles (``gid``,
``y`` m, ``v`` m/s, ``f`` N/m^3, ``theta``, rate state) and the bonds it counts that are not
fresh (``bond_i``, ``bond_j`` global numbers, ``broken``, ``rest``, ``slip`` m), attrs ``time``
(s), ``external_work`` and ``fracture_dissipated`` (J, this rank's parts); per particle force
with a state ``/forces/<i>``, its per-particle arrays ``<key>_<k>`` over the owned particles of
its body ``k`` with their global numbers ``gid_<k>``. A serial checkpoint holds its one part in
the checkpoint file itself; a run on K ranks writes ``checkpoint.g<step>.rank<R>.h5`` (R < K)
beside it (:mod:`pdfem.run.checkpoint` writes the manifest that makes a set valid).

Reading (:func:`restore_parts`): every rank opens every part, reads its global numbers chunk by
chunk (:data:`CHUNK` rows) and reads the values only over the span of rows it holds
(:class:`pdfem.pd.checkpoint.parts.PartPicker`), so no rank holds a global array.
"""

from __future__ import annotations

import re
from pathlib import Path

import h5py
import numpy as np

from pdfem.output.room import write_atomically
from pdfem.pd.checkpoint.parts import (BOND_KEYS, PARTICLE_KEYS, PartLayout, PartPicker, owned_part,
                                       locate, rank_scalars)

CHUNK = 1 << 20
"""Rows read at a time from a part (particles or listed bonds)."""

_PART = re.compile(r"^(?P<stem>.+)\.g(?P<gen>\d+)\.rank(?P<rank>\d+)\.h5(\.tmp)?$")


def part_path(manifest: Path, generation: int, rank: int) -> Path:
    """The part file of ``rank`` in checkpoint generation ``generation`` beside the manifest
    ``<out>/checkpoint.h5``: ``<out>/checkpoint.g<generation>.rank<rank>.h5``."""
    return manifest.with_name(f"{manifest.stem}.g{int(generation)}.rank{int(rank)}.h5")


def layout_of(body) -> PartLayout:
    """The rank's :class:`~pdfem.pd.checkpoint.parts.PartLayout` of an ice body."""
    return body.checkpoint_layout()


def _put(group: h5py.Group, state: dict) -> None:
    for k, v in state.items():
        if np.ndim(v) == 0:
            group.attrs[k] = v
        else:
            group.create_dataset(k, data=np.ascontiguousarray(v))


def write_part(f: h5py.File, bodies: list, forces: list) -> None:
    """Write this rank's part (ice bodies and particle-force states) into the open file ``f``."""
    for b in bodies:
        particles, bonds, scalars = owned_part(layout_of(b), b.checkpoint_state())
        g = f.create_group(f"ice/{b.name}")
        _put(g, {**particles, **bonds, **scalars})
    for i, force in enumerate(forces):
        state = force.checkpoint_state()
        if state:
            _put(f.create_group(f"forces/{i}"), state)


def write_part_file(path: Path, generation: int, rank: int, bodies: list, forces: list) -> int:
    """Write this rank's part to ``path`` (temporary file, fsync, ``os.replace``:
    :func:`pdfem.output.room.write_atomically`); returns its size in bytes.

    Raises
    ------
    OutputError
        The part could not be written; nothing of it is left.
    """
    def fill(f: h5py.File) -> None:
        f.attrs["generation"] = int(generation)
        f.attrs["rank"] = int(rank)
        write_part(f, bodies, forces)

    return write_atomically(path, fill, f"the checkpoint part of rank {rank}")


def remove_other_generations(manifest: Path, keep: int, parts: int) -> None:
    """Delete the part files (and left-over temporaries) beside ``manifest`` but those of
    ranks 0 .. ``parts`` - 1 of generation ``keep`` (all of them for ``parts`` = 0: a serial
    checkpoint); a run killed earlier may have left some of any generation."""
    for p in manifest.parent.iterdir():
        m = _PART.match(p.name)
        if m and m["stem"] == manifest.stem and (int(m["gen"]) != keep or p.name.endswith(".tmp")
                                                 or int(m["rank"]) >= parts):
            p.unlink(missing_ok=True)


def _rows(ds: h5py.Dataset, a: int, b: int) -> np.ndarray:
    return ds[a:b]


def _pick_ice(picker: PartPicker, g: h5py.Group) -> None:
    """Feed one part's group of a body to ``picker``, chunk by chunk, reading values only over
    the span of rows the rank holds."""
    n = g["gid"].shape[0]
    for a in range(0, n, CHUNK):
        hit, pos = picker.wanted(_rows(g["gid"], a, min(a + CHUNK, n)))
        rows = np.flatnonzero(hit)
        if len(rows):
            lo, hi = rows[0], rows[-1] + 1
            values = {k: _rows(g[k], a + lo, a + hi) for k in PARTICLE_KEYS if k in g}
            picker.take_particles(hit[lo:hi], pos[lo:hi], values)
    m = g["bond_i"].shape[0]
    for a in range(0, m, CHUNK):
        hit, _ = picker.wanted(_rows(g["bond_i"], a, min(a + CHUNK, m)))
        rows = np.flatnonzero(hit)
        if len(rows):
            lo, hi = a + rows[0], a + rows[-1] + 1
            values = {k: _rows(g[k], lo, hi) for k in ("bond_i", "bond_j", *BOND_KEYS) if k in g}
            picker.take_bonds(values)


def _scalars(g: h5py.Group) -> dict:
    return {k: float(v) for k, v in g.attrs.items()}


def restore_ice(parts: list[Path], body, rank: int, size: int) -> None:
    """Restore ``body`` (this rank's part of it) from the part files ``parts`` (rank order).

    Raises
    ------
    ValueError, KeyError
        If the parts do not hold the body's particles and bonds.
    """
    layout = layout_of(body)
    picker = PartPicker(layout, body.checkpoint_state())
    scalars = []
    for path in parts:
        with h5py.File(path, "r") as f:
            g = f[f"ice/{body.name}"]
            _pick_ice(picker, g)
            scalars.append(_scalars(g))
    body.restore_state(picker.state(rank_scalars(scalars, rank, size), body.name))


def restore_force(parts: list[Path], i: int, force) -> None:
    """Restore particle force ``i`` from the parts: per body ``k`` of ``force.bodies`` its
    arrays ``<key>_<k>`` in the local particle order of that body (rows of particles this rank
    does not hold are NaN), scalars from the first part.

    Raises
    ------
    ValueError
        If an owned particle's entry is missing.
    """
    state: dict = {}
    for k, b in enumerate(force.bodies):
        layout = layout_of(b)
        found = np.zeros(len(layout.gid), dtype=np.int64)
        for path in parts:
            with h5py.File(path, "r") as f:
                g = f[f"forces/{i}"]
                if not state:
                    state.update(_scalars(g))
                _pick_force(g, k, layout.gid, found, state)
        if np.any(found[layout.owned] != 1):
            raise ValueError(f"particle force {i}: the checkpoint's parts do not hold every "
                             f"particle of ice body '{b.name}' once")
    force.restore_state(state)


def _pick_force(g: h5py.Group, k: int, local: np.ndarray, found: np.ndarray,
                state: dict) -> None:
    """Put the rows of a part's force group for body ``k`` whose global numbers are among
    ``local`` into ``state`` (arrays in local order), chunk by chunk."""
    keys = [key for key in g if key.rsplit("_", 1)[-1] == str(k) and key != f"gid_{k}"]
    for key in keys:
        state.setdefault(key, np.full((len(local),) + g[key].shape[1:], np.nan))
    n = g[f"gid_{k}"].shape[0]
    for a in range(0, n, CHUNK):
        hit, pos = locate(local, _rows(g[f"gid_{k}"], a, min(a + CHUNK, n)))
        rows = np.flatnonzero(hit)
        if not len(rows):
            continue
        lo, hi = rows[0], rows[-1] + 1
        where = pos[lo:hi][hit[lo:hi]]
        found[where] += 1
        for key in keys:
            state[key][where] = _rows(g[key], a + lo, a + hi)[hit[lo:hi]]


def has_force_state(parts: list[Path], i: int) -> bool:
    """Whether the checkpoint holds a state of particle force ``i``."""
    with h5py.File(parts[0], "r") as f:
        return f"forces/{i}" in f
