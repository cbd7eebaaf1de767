"""Per-step histories of a results file: ``/<group>/time`` (K,) and ``/<group>/<key>`` (K, ...).

A run appends one row per coupling step to histories such as ``energy``, ``loads/<name>``
(force in N, moment in N m) or ``monitors/<probe>``. Rows are buffered in memory and reach
the file in blocks of ``HISTORY_BLOCK`` rows (also the chunk size), or at the next frame,
flush or close. A block is written in two phases: the key columns, then (after an HDF5 flush)
the time column, which commits the rows. ``time`` is filled with NaN where unwritten, so a
reader keeps the rows up to the first NaN time.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import h5py
import numpy as np

from pdfem.output.datasets import growing_dataset, has_committed, put_rows
from pdfem.output.layout import RESERVED, check_name

HISTORY_BLOCK = 1024
"""Rows per chunk of a history dataset, and rows buffered in memory before a block write."""


def first_row(group: str, values: Mapping[str, Any],
              existing: Iterable[str]) -> dict[str, np.ndarray]:
    """Validate the group name and first row of a new history; return the row as float64 arrays.

    Parameters
    ----------
    group
        History group, e.g. ``"energy"`` or ``"loads/<name>"`` (components are names of
        letters, digits, ``_ . + -``; the first must not be meta, time, ice, structure, xdmf).
    values
        The first row: scalars or arrays by key (``time`` is not a key).
    existing
        The history groups already in the file: the new one must not nest with them.

    Raises
    ------
    ValueError
        If a name is invalid, reserved, nests with an existing history, or a key is ``time``.
    """
    parts = group.split("/") if isinstance(group, str) else [group]
    for p in parts:
        check_name(p, "history group component")
    if parts[0] in RESERVED:
        raise ValueError(f"history group {group!r} would collide with /{parts[0]}")
    first = {check_name(k, "history key"): np.asarray(v, dtype=np.float64)
             for k, v in values.items()}
    clash = [g for g in existing if g.startswith(group + "/") or group.startswith(g + "/")]
    if clash:
        raise ValueError(f"history group {group!r} would nest with history {clash[0]!r}")
    if "time" in first:
        raise ValueError(f"history {group!r}: 'time' is not allowed as a key")
    return first


class History:
    """Buffered per-step rows of one history group.

    Parameters
    ----------
    file
        The results file, open for writing.
    path
        HDF5 path of the group, e.g. ``/loads/panel``.
    datasets
        The key columns, by key, each (K, ...).
    time
        The time column (K,), NaN where unwritten.
    written
        Rows already committed to the file.

    Use :meth:`create` for a new history and :meth:`resume` to continue one of a file.
    """

    def __init__(self, file: h5py.File, path: str, datasets: dict[str, h5py.Dataset],
                 time: h5py.Dataset, written: int) -> None:
        self.file = file
        self.path = path
        self.datasets = datasets
        self.time = time
        self.shapes = {k: ds.shape[1:] for k, ds in datasets.items()}
        self.buffers = {k: np.empty((HISTORY_BLOCK,) + s) for k, s in self.shapes.items()}
        self.times = np.empty(HISTORY_BLOCK)
        self.count = 0  # rows in the buffers
        self.written = written  # rows committed to the file

    @classmethod
    def create(cls, file: h5py.File, path: str, values: Mapping[str, np.ndarray]) -> History:
        """Create the group ``path`` with empty columns shaped like the row ``values``."""
        group = file.require_group(path)
        group.attrs["kind"] = "history"
        datasets = {k: growing_dataset(group, k, v.shape, HISTORY_BLOCK)
                    for k, v in values.items()}
        time = growing_dataset(group, "time", (), HISTORY_BLOCK, fillvalue=np.nan)
        return cls(file, path, datasets, time, 0)

    @classmethod
    def resume(cls, file: h5py.File, path: str, rows: int) -> History:
        """Take over an existing history group (append mode), cut to its first ``rows`` rows."""
        group = file[path]
        time = group["time"]
        if not has_committed(time, rows):
            raise ValueError(f"history {path!r} holds fewer than the {rows} committed rows to "
                             "resume from")
        datasets = {k: ds for k, ds in group.items() if k != "time"}
        for ds in (*datasets.values(), time):
            ds.resize(rows, axis=0)
        return cls(file, path, datasets, time, rows)

    def append(self, time: float, values: Mapping[str, Any]) -> bool:
        """Buffer one row; returns whether the buffer is full (then :meth:`write_block`)."""
        if values.keys() != self.shapes.keys():
            raise ValueError(f"history {self.path!r}: keys are fixed by the first row "
                             f"{sorted(self.shapes)}, got {sorted(values)}")
        c = self.count
        for k, v in values.items():
            # (the shape of a float or an array without numpy.shape's call: a row is written
            # every coupling step, some thirty groups of them)
            shape = (() if type(v) is float else v.shape if isinstance(v, (np.ndarray, np.generic))
                     else np.shape(v))
            if shape != self.shapes[k]:
                raise ValueError(f"history {self.path!r}: {k!r} has shape {np.shape(v)}, "
                                 f"expected {self.shapes[k]} as in the first row")
            self.buffers[k][c] = v
        self.times[c] = time
        self.count = c + 1
        return self.count == HISTORY_BLOCK

    def write_block(self) -> None:
        """Write and commit the buffered rows: key columns, flush, time column."""
        self.write_columns()
        self.file.flush()
        self.commit()

    def write_columns(self) -> None:
        """Phase 1: write the key columns of the buffered rows."""
        end = self.written + self.count
        for k, ds in self.datasets.items():
            if ds.shape[0] != end:
                put_rows(ds, self.written, self.buffers[k][:self.count])

    def commit(self) -> None:
        """Phase 2, after a flush that followed :meth:`write_columns`: write the time column."""
        if self.count:
            put_rows(self.time, self.written, self.times[:self.count])
            self.written += self.count
            self.count = 0

    @property
    def new_bytes(self) -> int:
        """Bytes writing the buffered rows adds to the file: a chunk of every column if they
        start a new one (a block of rows is one chunk), else nothing."""
        if not self.count:
            return 0
        first, last = self.written, self.written + self.count - 1
        if first % HISTORY_BLOCK and first // HISTORY_BLOCK == last // HISTORY_BLOCK:
            return 0
        return self.times.nbytes + sum(b.nbytes for b in self.buffers.values())

    @property
    def rows(self) -> int:
        """Rows appended so far, committed or buffered."""
        return self.written + self.count
