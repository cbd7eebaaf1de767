"""Datasets that grow along their first axis (frames, history rows): create, append, read back.

Frame fields, history columns and the time columns of a results file are all float64
datasets of shape ``(0, ...)`` at first, resizable along axis 0. A time column is filled with
NaN where unwritten, so its rows before the first NaN are the committed ones. A run killed
while flushing can leave the last rows' chunks past the file's recorded end; those rows
raise ``OSError`` when read, and :func:`readable_prefix` leaves them out.
"""

from __future__ import annotations

import h5py
import numpy as np


def growing_dataset(group: h5py.Group, name: str, item_shape: tuple[int, ...],
                    rows_per_chunk: int, fillvalue: float | None = None) -> h5py.Dataset:
    """Create an empty float64 dataset ``(0,) + item_shape``, resizable along axis 0.

    Parameters
    ----------
    group
        The group (or file) to create it in.
    name
        Its name in ``group``.
    item_shape
        The shape of one row.
    rows_per_chunk
        Rows per HDF5 chunk.
    fillvalue
        What unwritten rows read (HDF5's default 0 if ``None``); NaN for time columns.
    """
    return group.create_dataset(name, shape=(0,) + item_shape, maxshape=(None,) + item_shape,
                                chunks=(rows_per_chunk,) + item_shape, dtype=np.float64,
                                fillvalue=fillvalue)


def put_rows(ds: h5py.Dataset, start: int, rows: np.ndarray) -> None:
    """Resize ``ds`` to ``start + len(rows)`` rows and write ``rows`` from row ``start`` on."""
    end = start + len(rows)
    ds.resize(end, axis=0)
    ds[start:end] = rows


def has_committed(time: h5py.Dataset, n: int) -> bool:
    """Whether the time column ``time`` has at least ``n`` rows, none of them NaN (unwritten)."""
    return time.shape[0] >= n and not np.isnan(time[:n]).any()


def readable_prefix(ds: h5py.Dataset, n: int) -> np.ndarray:
    """Rows ``[:m]`` of ``ds`` for the largest ``m <= n`` that reads without error.

    Rows that raise ``OSError`` (see the module docstring) are dropped a chunk at a time from
    the end.
    """
    step = ds.chunks[0] if ds.chunks else n
    m = n
    while m > 0:
        try:
            return ds[:m]
        except OSError:
            m = (m - 1) // step * step
    return ds[:0]


def committed(time: np.ndarray) -> np.ndarray:
    """The rows of a time column before its first NaN (unwritten rows read NaN)."""
    bad = np.flatnonzero(np.isnan(time))
    return time[:bad[0]] if bad.size else time
