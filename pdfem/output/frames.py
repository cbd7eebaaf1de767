"""Per-frame fields of one body in a results file: dataset ``<body>/<field>`` of shape (F, n, ...).

Each output frame appends one row to every field of every body, and to ``x`` (F, n, 3), the
positions (reference + ``u``, m) that the XDMF file draws the body at. Every frame also gets, for
the XDMF file, a virtual dataset per field (:func:`pdfem.output.xdmf.create_view`). The
views are made ``VIEW_BATCH`` frames ahead, so the groups that hold them change only once per
batch: fewer chances for a run killed mid-flush to damage them (the reader never uses them).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import h5py
import numpy as np

from pdfem.output.datasets import growing_dataset, put_rows
from pdfem.output.layout import POSITIONS, check_name
from pdfem.output.xdmf import create_view

CHUNK_BYTES = 256 * 1024
"""Target size of a frame field's HDF5 chunk: as many frames per chunk as fit (at most
``MAX_FRAMES_PER_CHUNK``, at least 1). One frame per chunk made the chunk index (a B-tree)
grow by one entry per frame and the flush of every frame slower as the run went on (5-10x
after 6,000 frames, ``benchmarks/output_frames.py``); with a chunk of many frames the index
grows by one entry per chunk, and the chunk being filled stays in HDF5's chunk cache (1 MiB
per dataset by default)."""

MAX_FRAMES_PER_CHUNK = 64
"""Most frames in one chunk of a frame field."""


def frames_per_chunk(item_shape: tuple[int, ...]) -> int:
    """Frames per HDF5 chunk of a float64 field whose frame has shape ``item_shape``: a power
    of two with about ``CHUNK_BYTES`` per chunk, between 1 and ``MAX_FRAMES_PER_CHUNK``."""
    row = 8 * max(1, int(np.prod(item_shape)))
    rows = max(1, CHUNK_BYTES // row)
    return int(min(MAX_FRAMES_PER_CHUNK, 1 << (rows.bit_length() - 1)))


VIEW_BATCH = 64
"""Per-frame XDMF views are made this many frames ahead, so the groups that hold them change
(and can be damaged by a kill during the flush) only every VIEW_BATCH frames."""


class FrameSeries:
    """Fields of one group, one output frame per row: dataset ``<path>/<field>`` is (F, n, ...).

    Parameters
    ----------
    file
        The results file, open for writing.
    path
        HDF5 path of the body's group, e.g. ``/ice/sheet``.
    sizes
        XDMF centre ("Node", and "Cell" for a mesh with elements) -> number of items.
    item_shapes
        The allowed shapes of one item, e.g. ``((), (3,))``.
    required
        Fields the first frame must have.
    cell_fields
        Field names centred on the cells (if the body has cells); all others are on the nodes.
    positions
        (n, 3) reference positions of the nodes (m), or ``None``: each frame then also records
        the field ``x`` = ``positions`` + ``u`` (the frame's ``u`` is required; a frame may not
        give ``x`` itself).

    Notes
    -----
    A field's leading dimension must be its centre's size. The field set and each field's
    shape are fixed by the first frame. Frame ``j`` of field ``k`` is shown by the view
    ``/xdmf<path>/<k>/<j:06d>``; views made ahead and never used are deleted on close.
    """

    def __init__(self, file: h5py.File, path: str, sizes: Mapping[str, int],
                 item_shapes: tuple[tuple[int, ...], ...], required: tuple[str, ...],
                 cell_fields: frozenset[str] = frozenset(),
                 positions: np.ndarray | None = None) -> None:
        self.file = file
        self.positions = positions
        self.cell_fields = cell_fields
        self.path = path
        self.sizes = dict(sizes)
        self.item_shapes = item_shapes
        self.required = required
        # field name -> (centre, item shape), fixed by the first frame
        self.fields: dict[str, tuple[str, tuple[int, ...]]] | None = None
        self._datasets: dict[str, h5py.Dataset] = {}
        self._view_groups: dict[str, h5py.Group] = {}
        self._views = 0  # frames 0 .. _views - 1 have views

    def _centre(self, name: str, shape: tuple[int, ...]) -> str:
        centre = "Cell" if name in self.cell_fields and "Cell" in self.sizes else "Node"
        n = self.sizes[centre]
        if shape[:1] == (n,) and shape[1:] in self.item_shapes:
            return centre
        allowed = " or ".join(str((n,) + s) for s in self.item_shapes)
        raise ValueError(f"field {name!r} of {self.path} has shape {shape}, expected {allowed} "
                         f"({'one per cell' if centre == 'Cell' else 'one per node'})")

    def check(self, values: Mapping[str, Any]) -> dict[str, np.ndarray]:
        """Validate one frame's fields; return them as C-contiguous float64 arrays."""
        arrays = {check_name(k, "field"): np.ascontiguousarray(v, dtype=np.float64)
                  for k, v in values.items()}
        if self.positions is not None and POSITIONS in arrays:
            raise ValueError(f"{self.path}: field {POSITIONS!r} is recorded by the writer "
                             "(reference positions + u); do not give it")
        if self.fields is None:
            missing = [k for k in self.required if k not in arrays]
            if missing:
                raise ValueError(f"{self.path}: the first frame lacks the required fields "
                                 f"{missing}")
            for k, a in arrays.items():
                self._centre(k, a.shape)
        else:
            missing = sorted(set(self.fields) - set(arrays) - {POSITIONS})
            extra = sorted(set(arrays) - set(self.fields))
            if missing or extra:
                raise ValueError(f"{self.path}: the field set is fixed by the first frame "
                                 f"{sorted(self.fields)}; missing {missing}, unexpected {extra}")
            for k, a in arrays.items():
                n = self.sizes[self.fields[k][0]]
                if a.shape != (n,) + self.fields[k][1]:
                    raise ValueError(f"field {k!r} of {self.path} has shape {a.shape}, "
                                     f"expected {(n,) + self.fields[k][1]}")
        if self.positions is not None:
            arrays[POSITIONS] = self.positions + arrays["u"]
        return arrays

    def append(self, index: int, arrays: Mapping[str, np.ndarray]) -> None:
        """Write frame ``index`` (the arrays were validated by :meth:`check`)."""
        if self.fields is None:
            self.fields = {}
            group = self.file[self.path]
            for k, a in arrays.items():
                self.fields[k] = (self._centre(k, a.shape), a.shape[1:])
                self._datasets[k] = growing_dataset(group, k, a.shape, frames_per_chunk(a.shape))
                self._view_groups[k] = self.file.create_group(f"/xdmf{self.path}/{k}")
        for k, a in arrays.items():
            put_rows(self._datasets[k], index, a[np.newaxis])
        if index >= self._views:
            for k, a in arrays.items():
                for j in range(index, index + VIEW_BATCH):
                    create_view(self._view_groups[k], self._datasets[k], j, a.shape)
            self._views = index + VIEW_BATCH

    def views_due(self, index: int) -> bool:
        """Whether writing frame ``index`` makes a batch of views."""
        return index >= self._views

    def resume(self, n_frames: int) -> None:
        """Take over the datasets of an existing file (append mode), cut to ``n_frames`` frames;
        views of later frames are deleted (they are made again as frames are added)."""
        group = self.file[self.path]
        names = [k for k, ds in group.items()
                 if isinstance(ds, h5py.Dataset) and ds.maxshape[0] is None]
        if not names:
            return
        if self.positions is not None and POSITIONS not in names:
            raise ValueError(f"{self.path} has no per-frame positions {POSITIONS!r} (a file of "
                             "an older pdfem): it cannot be continued; start the run again")
        self.fields = {}
        for k in names:
            ds = group[k]
            if ds.shape[0] < n_frames:
                raise ValueError(f"{self.path}/{k} has {ds.shape[0]} frames, fewer than the "
                                 f"{n_frames} to resume from")
            self.fields[k] = (self._centre(k, ds.shape[1:]), ds.shape[2:])
            ds.resize(n_frames, axis=0)
            self._datasets[k] = ds
            views = self.file.require_group(f"/xdmf{self.path}/{k}")
            for v in [v for v in views if int(v) >= n_frames]:
                del views[v]
            self._view_groups[k] = views
        self._views = n_frames

    def drop_unused_views(self, n_frames: int) -> None:
        """Delete the views made ahead for frames that were never written."""
        for group in self._view_groups.values():
            for j in range(n_frames, self._views):
                del group[f"{j:06d}"]
        self._views = min(self._views, n_frames)
