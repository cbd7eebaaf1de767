"""Checkpoints of a run: everything needed to continue it, written so a kill never spoils one.

The checkpoint file ``<out>/checkpoint.h5`` (the *manifest*, replaced each time) holds, at the
end of a coupling step:

- ``/driver`` attrs: the clock and output counters (:class:`DriverState`: step, time, coupling
  step and substep counts, next output time, frames written, broken bonds, the initial energy
  of the energy balance) and, in ``/driver/history_rows``, the rows of every results history;
- ``/structure/<name>``: the ``checkpoint_state()`` of each structure (elastic: u, v, a, v_half, f_ext,
  f_damp, time, surface_forces; rigid: time, time_carry, surface_forces; ship: c, q, v, L,
  time, thrust and surge work, surface_forces);
- ``/coupler``: :meth:`pdfem.coupling.coupler.Coupler.checkpoint_state` (time, pending contact loads,
  contact work counters, last pair loads; per-rank counters as totals and ``<key>_ranks``);
- ``/bodies`` attrs: each ice body's particle count;
- root attrs ``format``, ``pdfem_version``, ``case_sha256`` (SHA-256 of the case text: a
  checkpoint refuses to restart another case), ``generation`` (the step) and ``parts``.

The ice and the particle forces' per-particle state (water) are stored in *parts*, one per rank
that wrote them (:mod:`pdfem.run.checkpoint_ranks`: owned particles and non-fresh bonds under
their global numbers). A run on K ranks (K = 1 serially) has every rank write
``checkpoint.g<step>.rank<R>.h5``; rank 0 then writes the manifest, naming the K files with
their sizes (``/part_sizes`` dataset), LAST: written to
``checkpoint.h5.tmp``, fsync'ed, moved over the old one with ``os.replace``; only then are the
previous generation's part files deleted. A run killed at any moment therefore leaves a valid
set: the previous manifest with its parts, or the new one with its parts. A write that fails
(no space left, a file-size limit, an I/O error: :func:`pdfem.output.room.write_atomically`)
removes its temporary file, leaves the previous checkpoint whole, and raises
:class:`pdfem.errors.OutputError` saying which checkpoint a restart will use.

A restart on N ranks from a checkpoint of M ranks (or serial <-> parallel): every rank reads the
manifest, then from every part only the particles and bonds it holds, so no rank holds a global
array. Counters each rank keeps for its own particles continue bit for bit on as many ranks; on
another count rank 0 takes their totals, which changes only the rounding of their sums.

Scalars are attributes, arrays datasets. Restoring sets every array bit for bit, so a restart on
as many ranks continues exactly as the uninterrupted run would. :data:`FORMAT` 2 (per-rank
parts); a checkpoint of format 1 (pdfem before per-rank parts) is refused (exit 2). A manifest
with ``parts`` = 0 (serial checkpoints of earlier versions) holds its one part itself.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, field
from pathlib import Path

import h5py
import numpy as np

from pdfem import __version__
from pdfem.errors import InputError, OutputError
from pdfem.output.room import write_atomically
from pdfem.run.checkpoint_ranks import (has_force_state, part_path, remove_other_generations,
                                        restore_force, restore_ice, write_part_file)

FORMAT = 2
"""Checkpoint format version; a checkpoint of another version is refused."""

CHECKPOINT_NAME = "checkpoint.h5"
"""File name of the checkpoint (the manifest) in the output directory."""


def before_manifest(generation: int) -> None:
    """Called on every rank once all part files of checkpoint ``generation`` are on disk and
    before rank 0 writes the manifest that makes them valid: a run that dies here must restart
    from the previous checkpoint (tests replace this hook to raise, as a crash would)."""


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
    """A checkpoint's manifest read back: the driver counters, the shared state and the part
    files holding the ice (read by :func:`restore`, each rank its own particles)."""

    path: Path
    driver: DriverState
    bodies: dict[str, int]
    structures: dict[str, dict]
    coupler: dict
    parts: list[Path] = field(default_factory=list)


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
                     structures: list, coupler, comm) -> Path | None:
    """Write a checkpoint so that a kill at any moment leaves the previous or the new one whole.

    Every rank calls this. Each rank writes its part file (generation ``driver.step``), then
    rank 0 the manifest naming them, then removes the older generation.

    Parameters
    ----------
    path
        The checkpoint file (the manifest; replaced).
    case_text
        The case's TOML text (its hash is stored).
    driver
        Clock and output counters.
    bodies, structures
        The ice bodies and the structures (with ``checkpoint_state()``).
    coupler
        The :class:`pdfem.coupling.coupler.Coupler` (its ``forces`` with ``checkpoint_state()``).
    comm
        The communicator (rank 0 writes the manifest).

    Returns
    -------
    Path or None
        ``path`` (``None`` on ranks other than 0).

    Raises
    ------
    OutputError
        A part or the manifest could not be written; the previous checkpoint is kept whole
        (the message names it). Under MPI the failing rank ends the job
        (:func:`pdfem.parallel.comm.run_guarded`).
    """
    path, gen = Path(path), int(driver.step)
    with _keeping(path):
        mine = write_part_file(part_path(path, gen, comm.rank), gen, comm.rank, bodies,
                               coupler.forces)
    sizes = comm.gather(mine)  # every part is on disk before the manifest names it
    before_manifest(gen)
    coupler_state = coupler.checkpoint_state()  # collective under MPI
    if comm.rank != 0:
        return None

    def fill(f: h5py.File) -> None:
        f.attrs["format"] = FORMAT
        f.attrs["pdfem_version"] = __version__
        f.attrs["case_sha256"] = case_hash(case_text)
        f.attrs["generation"] = gen
        f.attrs["parts"] = len(sizes)
        f.create_dataset("part_sizes", data=np.array(sizes, dtype=np.int64))
        d = f.create_group("driver")
        values = asdict(driver)
        rows = values.pop("history_rows")
        _put(d, values)
        h = d.create_group("history_rows")
        for k, n in rows.items():
            h.attrs[k] = int(n)
        g = f.create_group("bodies")
        for b in bodies:
            g.attrs[b.name] = int(b.n_global)
        for s in structures:
            _put(f.create_group(f"structure/{s.name}"), s.checkpoint_state())
        _put(f.create_group("coupler"), coupler_state)

    with _keeping(path):
        write_atomically(path, fill, f"the checkpoint of step {gen:,}")
    _fsync_dir(path.parent)
    remove_other_generations(path, gen, len(sizes))
    return path


@contextmanager
def _keeping(path: Path) -> Iterator[None]:
    """Add to a failed checkpoint write's message what it leaves: the previous checkpoint at
    ``path``, if any."""
    try:
        yield
    except OutputError as exc:
        try:
            with h5py.File(path, "r") as f:
                step = int(f["driver"].attrs["step"])
        except (OSError, KeyError):
            raise OutputError(f"{exc} There is no earlier checkpoint; the results written so "
                              "far are kept.") from None
        raise OutputError(f"{exc} The previous checkpoint {path} (step {step:,}) is kept "
                          "whole: restart from it with --restart once there is room.") from None


def _fsync_dir(folder: Path) -> None:
    """Make a rename in ``folder`` durable (where the platform allows it)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def read_checkpoint(path: str | os.PathLike, case_text: str, case_file: str) -> Checkpoint:
    """Read a checkpoint's manifest, check that it belongs to the case and that its part files
    are there whole (the ice itself is read by :func:`restore`).

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
        If the file is missing, not a pdfem checkpoint, of another format, of another case, or
        one of its part files is missing or of another size than the manifest records.
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
                             f"{FORMAT} this pdfem {__version__} reads (format 1, one file "
                             "gathered on rank 0, came before per-rank parts): continue it with "
                             "the pdfem version that wrote it, or start the run again")
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
        bodies = {k: int(v) for k, v in f["bodies"].attrs.items()}
        structures = {k: _get(g) for k, g in f.get("structure", {}).items()}
        coupler = _get(f["coupler"])
        gen, n_parts = int(f.attrs["generation"]), int(f.attrs["parts"])
        sizes = f["part_sizes"][()] if n_parts else []
    parts = [part_path(p, gen, r) for r in range(n_parts)] or [p]
    for r, size in enumerate(sizes):
        q = parts[r]
        if not q.is_file() or q.stat().st_size != int(size):
            raise InputError(str(p), where, f"its part file {q.name} (rank {r} of {n_parts}) is "
                             f"{'missing' if not q.is_file() else 'not the size it recorded'}; "
                             "keep the checkpoint.g<step>.rank<R>.h5 files the manifest names "
                             "beside it")
    return Checkpoint(p, driver, bodies, structures, coupler, parts)


def restore(checkpoint: Checkpoint, bodies: list, structures: list, coupler, comm) -> None:
    """Put the state of a checkpoint into freshly built bodies, structures and coupler; every
    rank takes its own particles and bonds from the parts (collective under MPI).

    Raises
    ------
    InputError
        If the bodies or structures do not match the checkpoint's (names or sizes).
    """
    names = sorted(b.name for b in bodies), sorted(s.name for s in structures)
    if names != (sorted(checkpoint.bodies), sorted(checkpoint.structures)):
        raise InputError(str(checkpoint.path), "--restart",
                         f"the checkpoint holds ice {sorted(checkpoint.bodies)} and structures "
                         f"{sorted(checkpoint.structures)}, the case {names[0]} and {names[1]}")
    try:
        for b in bodies:
            if b.n_global != checkpoint.bodies[b.name]:
                raise ValueError(f"ice body '{b.name}' has {checkpoint.bodies[b.name]} "
                                 f"particles in the checkpoint, {b.n_global} in the case")
            restore_ice(checkpoint.parts, b, comm.rank, comm.size)
        for s in structures:
            s.restore_state(checkpoint.structures[s.name])
        coupler.restore_state(checkpoint.coupler)
        for i, force in enumerate(coupler.forces):
            if has_force_state(checkpoint.parts, i):
                restore_force(checkpoint.parts, i, force)
    except (KeyError, ValueError) as exc:
        raise InputError(str(checkpoint.path), "--restart",
                         f"the checkpoint does not fit the case's bodies: {exc}") from None
