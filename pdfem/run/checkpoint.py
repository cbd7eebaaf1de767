"""Checkpoints of a run: everything needed to continue it, written atomically.

A checkpoint is one HDF5 file (``<out>/checkpoint.h5``, replaced each time) holding, at the end
of a coupling step:

- ``/driver`` attrs: the clock and output counters (:class:`DriverState`: step, time, coupling
  step and substep counts, next output time, frames written, broken bonds, the initial energy
  of the energy balance) and, in ``/driver/history_rows``, the rows of every results history;
- ``/ice/<body>``: the state of each ice body, in global particle and bond order whatever the
  number of MPI ranks: datasets ``y`` (m), ``v`` (m/s), ``f`` (N/m^3), ``broken`` (uint8 per
  bond), ``theta``; attrs ``time`` (s), ``external_work`` (J, the work of the velocity
  constraints) and, from a run on several ranks, ``external_work_ranks`` (each rank's part);
- ``/structure/<name>``: the ``checkpoint_state()`` of each structure (elastic: u, v, a, v_half, f_ext,
  f_damp, time, surface_forces; rigid: time, time_carry, surface_forces; ship: c, q, v, L,
  time, thrust and surge work, surface_forces);
- ``/coupler``: :meth:`pdfem.coupling.coupler.Coupler.checkpoint_state` (time, pending contact loads,
  contact work counters, last pair loads);
- ``/forces/<i>``: the ``checkpoint_state()`` of the coupler's particle forces that keep one
  (water: drag loss and water kinetic energy per particle, J, in global order);
- root attrs ``format``, ``pdfem_version``, ``case_sha256`` (SHA-256 of the case text: a
  checkpoint refuses to restart another case).

A run on several ranks gathers the state to rank 0, which writes the file; counters that each
rank keeps for its own particles are stored as totals and per rank (``<key>_ranks``). A restart
on as many ranks continues bit for bit; on another rank count (or serially) it continues with
the totals on rank 0, which changes only the rounding of those counters' sums.

Scalars are attributes, arrays datasets, all float64 except ``broken``. The file is written to
``<name>.tmp``, fsync'ed, then moved over the old one with ``os.replace``: a run killed at any
moment leaves the previous or the new checkpoint whole, never a mix. Restoring sets every array
bit for bit, so a restarted run continues exactly as the uninterrupted one would.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

import h5py
import numpy as np

from pdfem import __version__
from pdfem.errors import InputError

FORMAT = 1
"""Checkpoint format version; a checkpoint of another version is refused."""

CHECKPOINT_NAME = "checkpoint.h5"
"""File name of the checkpoint in the output directory."""


@dataclass
class DriverState:
    """The time loop's clock and output counters at the end of a coupling step (SI)."""

    step: int
    time: float
    time_step: float
    ice_substeps: int
    structure_substeps: int
    next_output: float
    frames: int
    broken: int
    initial_energy: float
    history_rows: dict[str, int] = field(default_factory=dict)


@dataclass
class Checkpoint:
    """A checkpoint read back: the driver counters and the state of every part."""

    path: Path
    driver: DriverState
    ice: dict[str, dict]
    structures: dict[str, dict]
    coupler: dict
    forces: dict = field(default_factory=dict)


def case_hash(text: str) -> str:
    """SHA-256 (hex) of a case's TOML text."""
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _put(group: h5py.Group, state: dict) -> None:
    for k, v in state.items():
        if np.ndim(v) == 0:
            group.attrs[k] = v
        else:
            group.create_dataset(k, data=np.ascontiguousarray(v))


def _get(group: h5py.Group) -> dict:
    out = {k: (v.item() if isinstance(v, np.generic) else v) for k, v in group.attrs.items()}
    out.update({k: ds[()] for k, ds in group.items() if isinstance(ds, h5py.Dataset)})
    return out


def write_checkpoint(path: str | os.PathLike, case_text: str, driver: DriverState, bodies: list,
                     structures: list, coupler, rank: int = 0) -> Path | None:
    """Write a checkpoint atomically (temporary file, fsync, ``os.replace``).

    With ice bodies split over MPI ranks every rank calls this: each body's and the coupler's
    ``checkpoint_state()`` gathers the whole state (in global particle and bond order, the same
    file a serial run writes) on rank 0, which writes the file.

    Parameters
    ----------
    path
        The checkpoint file (replaced).
    case_text
        The case's TOML text (its hash is stored).
    driver
        Clock and output counters.
    bodies, structures
        The ice bodies and the structures (with ``checkpoint_state()``).
    coupler
        The :class:`pdfem.coupling.coupler.Coupler`.
    rank
        This process's MPI rank (only rank 0 writes).

    Returns
    -------
    Path or None
        ``path`` (``None`` on ranks other than 0).
    """
    ice = [(b.name, b.checkpoint_state()) for b in bodies]  # collective under MPI
    coupler_state = coupler.checkpoint_state()  # collective under MPI
    forces = [f.checkpoint_state() for f in coupler.forces]  # collective under MPI
    if rank != 0:
        return None
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    with h5py.File(tmp, "w") as f:
        f.attrs["format"] = FORMAT
        f.attrs["pdfem_version"] = __version__
        f.attrs["case_sha256"] = case_hash(case_text)
        d = f.create_group("driver")
        values = asdict(driver)
        rows = values.pop("history_rows")
        _put(d, values)
        h = d.create_group("history_rows")
        for k, n in rows.items():
            h.attrs[k] = int(n)
        for name, state in ice:
            _put(f.create_group(f"ice/{name}"), state)
        for s in structures:
            _put(f.create_group(f"structure/{s.name}"), s.checkpoint_state())
        _put(f.create_group("coupler"), coupler_state)
        for i, state in enumerate(forces):
            if state:
                _put(f.create_group(f"forces/{i}"), state)
    with open(tmp, "rb+") as fh:
        os.fsync(fh.fileno())
    os.replace(tmp, path)
    return path


def read_checkpoint(path: str | os.PathLike, case_text: str, case_file: str) -> Checkpoint:
    """Read a checkpoint and check that it belongs to the case.

    Parameters
    ----------
    path
        The checkpoint file.
    case_text
        The TOML text of the case being restarted.
    case_file
        The case file's name (for messages).

    Raises
    ------
    InputError
        If the file is missing, not a pdfem checkpoint, of another format, or of another case.
    """
    p = Path(path)
    where = "--restart"
    if not p.is_file():
        raise InputError(str(p), where, "no such checkpoint file")
    try:
        f = h5py.File(p, "r")
    except (OSError, BlockingIOError) as exc:
        raise InputError(str(p), where, f"not a readable checkpoint (HDF5) file: {exc}") from None
    with f:
        if "driver" not in f or "case_sha256" not in f.attrs:
            raise InputError(str(p), where, "not a pdfem checkpoint (no /driver or case hash)")
        fmt = int(f.attrs.get("format", -1))
        if fmt != FORMAT:
            raise InputError(str(p), where, f"checkpoint format {fmt} is not the format "
                             f"{FORMAT} this pdfem {__version__} reads")
        stored = f.attrs["case_sha256"]
        stored = stored.decode() if isinstance(stored, bytes) else str(stored)
        if stored != case_hash(case_text):
            raise InputError(str(p), where, f"this checkpoint belongs to another case (or to an "
                             f"earlier version of {case_file}): the case text's SHA-256 differs; "
                             "restart with the case file that wrote it, unchanged")
        d = _get(f["driver"])
        rows = {k: int(v) for k, v in f["driver/history_rows"].attrs.items()}
        driver = DriverState(int(d["step"]), float(d["time"]), float(d["time_step"]),
                             int(d["ice_substeps"]), int(d["structure_substeps"]),
                             float(d["next_output"]), int(d["frames"]), int(d["broken"]),
                             float(d["initial_energy"]), rows)
        ice = {k: _get(g) for k, g in f.get("ice", {}).items()}
        structures = {k: _get(g) for k, g in f.get("structure", {}).items()}
        coupler = _get(f["coupler"])
        forces = {int(k): _get(g) for k, g in f.get("forces", {}).items()}
    return Checkpoint(p, driver, ice, structures, coupler, forces)


def restore(checkpoint: Checkpoint, bodies: list, structures: list, coupler) -> None:
    """Put the state of a checkpoint into freshly built bodies, structures and coupler.

    Raises
    ------
    InputError
        If the bodies or structures do not match the checkpoint's (names or sizes).
    """
    names = sorted(b.name for b in bodies), sorted(s.name for s in structures)
    if names != (sorted(checkpoint.ice), sorted(checkpoint.structures)):
        raise InputError(str(checkpoint.path), "--restart",
                         f"the checkpoint holds ice {sorted(checkpoint.ice)} and structures "
                         f"{sorted(checkpoint.structures)}, the case {names[0]} and {names[1]}")
    try:
        for b in bodies:
            b.restore_state(checkpoint.ice[b.name])
        for s in structures:
            s.restore_state(checkpoint.structures[s.name])
        coupler.restore_state(checkpoint.coupler)
        for i, force in enumerate(coupler.forces):
            if i in checkpoint.forces:
                force.restore_state(checkpoint.forces[i])
    except (KeyError, ValueError) as exc:
        raise InputError(str(checkpoint.path), "--restart",
                         f"the checkpoint does not fit the case's bodies: {exc}") from None
