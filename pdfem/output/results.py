"""Results file of a run: HDF5 written frame by frame, with an XDMF file beside it for ParaView.

The time loop creates one :class:`ResultsWriter`, registers the ice bodies, then calls
:meth:`ResultsWriter.write_frame` at every output time and :meth:`ResultsWriter.append_history`
at every step. :func:`read_results` loads a whole file into numpy arrays for tests and
post-processing.

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
    /ice/<body>/<field>      (F, N) or (F, N, 3)  any further per-particle field, e.g. theta
    /structure/<name>/points (Nn, 3)   reference node positions, m
    /structure/<name>/cells  (Ne, k)   int32 connectivity (VTK node order); attr cell_type
                             ("tetra", "hexahedron", "triangle" or "quad")
    /structure/<name>/u      (F, Nn, 3) nodal displacement, m
    /structure/<name>/von_mises (F, Ne) element von Mises stress, Pa (elastic structures)
    /structure/<name>/<field> (F, Nn or Ne) or (F, Nn or Ne, 3)  any further node or cell field
    /<history>/time          (K,)      e.g. /energy/time, /loads/<name>/time: step times, s
    /<history>/<key>         (K,) or (K, 3)  e.g. /energy/kinetic in J, /loads/<name>/force in N,
                             /loads/<name>/moment in N m
    /xdmf/...                per-frame views for the XDMF file (see below), no data of their own

Frame fields are float64, chunked one frame per chunk and resizable along the frame axis.
Histories are float64, chunked by ``HISTORY_BLOCK`` rows, and written in blocks: rows are kept
in memory until a block is full or until the next frame, :meth:`~ResultsWriter.flush` or
:meth:`~ResultsWriter.close`. Groups carry an attribute ``kind`` ("ice_body", "structure" or
"history") so readers can find them.

``<stem>.xdmf`` (XDMF 3) has one temporal collection per body; each frame is a uniform grid:
for an ice body Polyvertex topology over its particles and geometry ``x0``, for a structure
its elements (Tetrahedron, Hexahedron, Triangle or Quadrilateral) and geometry ``points``;
one attribute per field (Scalar or Vector, centred on the nodes or, for fields such as
``von_mises``, on the cells). The HDF5 file is named relative to the XDMF
file, so the two can be moved together. Each attribute references a per-frame dataset
``/xdmf/ice/<body>/<field>/<frame>``: an HDF5 virtual dataset that maps frame F of the
(F, N, ...) dataset (no copy). meshio's ``TimeSeriesReader`` cannot read XDMF hyperslabs;
it and VTK's ``vtkXdmfReader`` (ParaView's XDMF reader) both read these views. The views are
made ``VIEW_BATCH`` frames ahead, so the groups that hold them change only once per batch:
fewer chances for a run killed mid-flush to damage them (read_results never uses them).

Robustness: the file stays open (HDF5's default, oldest file format) and every frame is
committed in steps, each ended by a flush: its fields and the pending history columns; the
histories' time rows; its ``/time`` row. Then the XDMF file is rewritten atomically
(temporary file, ``os.replace``). Time datasets read NaN where unwritten, so a finite time
row means its data reached the file, and a committed frame means every history row appended
before it did too.
A process killed after :meth:`~ResultsWriter.write_frame` returns leaves a pair that h5py,
meshio and ParaView read, with every frame so far; one killed inside it may lose that frame,
and :func:`read_results` returns only committed rows that read back. Not used, by
measurement: ``libver="latest"`` (a killed writer leaves the file marked open for writing and
HDF5 refuses to open it without ``h5clear``) and SWMR (no new objects may be created once it
starts, but views and histories are added as the run goes). Neither file is fsync'ed: this
protects against the death of the process, not of the machine. While it is written the file
holds HDF5's lock, and a second :class:`ResultsWriter` on it is refused (HDF5 itself would
truncate it first); to read it during a run, start the reader (e.g. ParaView) with
``HDF5_USE_FILE_LOCKING=FALSE`` (:func:`read_results` does this itself).

Restart: ``ResultsWriter(path, case_text, append=True)`` reopens the file of a run (killed or
not) of the same case; after the bodies are registered again, :meth:`ResultsWriter.resume`
cuts every frame dataset and history back to the counts a checkpoint recorded (frames and
rows written after it are dropped, as are their XDMF views), rewrites the XDMF file, and the
run continues appending as before.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from datetime import datetime, timezone
from pathlib import Path
from typing import Any
from xml.sax.saxutils import escape, quoteattr

import h5py
import numpy as np

import pdfem

HISTORY_BLOCK = 1024
"""Rows per chunk of a history dataset, and rows buffered in memory before a block write."""

VIEW_BATCH = 64
"""Per-frame XDMF views are made this many frames ahead, so the groups that hold them change
(and can be damaged by a kill during the flush) only every VIEW_BATCH frames."""

REQUIRED_ICE_FIELDS = ("u", "v", "damage")
"""Fields every ice body must give in every frame."""

REQUIRED_STRUCTURE_FIELDS = ("u",)
"""Fields every structure must give in every frame."""

CELL_FIELDS = frozenset({"von_mises"})
"""Structure fields centred on the cells (elements); all others are nodal."""

XDMF_TOPOLOGY = {"tetra": ("Tetrahedron", 4), "hexahedron": ("Hexahedron", 8),
                 "triangle": ("Triangle", 3), "quad": ("Quadrilateral", 4)}
"""meshio cell type -> (XDMF topology type, nodes per cell); node order as in VTK."""

_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.+\-]*\Z")
_RESERVED = frozenset({"meta", "time", "ice", "structure", "xdmf"})
_ATTRIBUTE_TYPE = {(): "Scalar", (3,): "Vector"}


def _check_name(name: str, what: str) -> str:
    """Return ``name`` if it is a plain HDF5 link name (letters, digits, ``_ . + -``)."""
    if not isinstance(name, str) or not _NAME.match(name):
        raise ValueError(
            f"{what} {name!r} is not a valid name: use letters, digits, '_', '.', '+', '-' "
            "and start with a letter, digit or '_'"
        )
    return name


def _dims(shape: tuple[int, ...]) -> str:
    return " ".join(str(int(n)) for n in shape)


def _data_item(h5name: str, path: str, shape: tuple[int, ...], number_type: str = "Float",
               precision: int = 8) -> str:
    """XDMF DataItem referencing the whole HDF5 dataset ``path`` of file ``h5name``."""
    return (f'<DataItem Dimensions="{_dims(shape)}" NumberType="{number_type}" '
            f'Precision="{precision}" Format="HDF">{escape(h5name)}:{escape(path)}</DataItem>')


class _FrameSeries:
    """Fields of one group, one output frame per row: dataset ``<path>/<field>`` is (F, n, ...).

    ``sizes`` maps an XDMF centre ("Node", and "Cell" for a mesh with elements) to the number
    of items; a field is centred on the cells if its name is in ``cell_fields``, else on the
    nodes, and its leading dimension must be that centre's size. The field set and each
    field's shape are fixed by the first frame. Every frame also gets a virtual dataset
    ``/xdmf<path>/<field>/<frame>`` that maps that frame, for the XDMF file; these are made
    ``VIEW_BATCH`` frames ahead, and those never used are deleted on close.
    """

    def __init__(self, file: h5py.File, path: str, sizes: Mapping[str, int],
                 item_shapes: tuple[tuple[int, ...], ...], required: tuple[str, ...],
                 cell_fields: frozenset[str] = frozenset()) -> None:
        self.file = file
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
        arrays = {_check_name(k, "field"): np.ascontiguousarray(v, dtype=np.float64)
                  for k, v in values.items()}
        if self.fields is None:
            missing = [k for k in self.required if k not in arrays]
            if missing:
                raise ValueError(f"{self.path}: the first frame lacks the required fields "
                                 f"{missing}")
            for k, a in arrays.items():
                self._centre(k, a.shape)
        else:
            missing = sorted(set(self.fields) - set(arrays))
            extra = sorted(set(arrays) - set(self.fields))
            if missing or extra:
                raise ValueError(f"{self.path}: the field set is fixed by the first frame "
                                 f"{sorted(self.fields)}; missing {missing}, unexpected {extra}")
            for k, a in arrays.items():
                n = self.sizes[self.fields[k][0]]
                if a.shape != (n,) + self.fields[k][1]:
                    raise ValueError(f"field {k!r} of {self.path} has shape {a.shape}, "
                                     f"expected {(n,) + self.fields[k][1]}")
        return arrays

    def append(self, index: int, arrays: Mapping[str, np.ndarray]) -> None:
        """Write frame ``index`` (the arrays were validated by :meth:`check`)."""
        if self.fields is None:
            self.fields = {}
            group = self.file[self.path]
            for k, a in arrays.items():
                self.fields[k] = (self._centre(k, a.shape), a.shape[1:])
                self._datasets[k] = group.create_dataset(
                    k, shape=(0,) + a.shape, maxshape=(None,) + a.shape, chunks=(1,) + a.shape,
                    dtype=np.float64)
                self._view_groups[k] = self.file.create_group(f"/xdmf{self.path}/{k}")
        for k, a in arrays.items():
            ds = self._datasets[k]
            ds.resize(index + 1, axis=0)
            ds[index] = a
        if index >= self._views:
            for k, a in arrays.items():
                for j in range(index, index + VIEW_BATCH):
                    self._create_view(k, j, a.shape)
            self._views = index + VIEW_BATCH

    def resume(self, n_frames: int) -> None:
        """Take over the datasets of an existing file (append mode), cut to ``n_frames`` frames;
        views of later frames are deleted (they are made again as frames are added)."""
        group = self.file[self.path]
        names = [k for k, ds in group.items()
                 if isinstance(ds, h5py.Dataset) and ds.maxshape[0] is None]
        if not names:
            return
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

    def _create_view(self, name: str, index: int, shape: tuple[int, ...]) -> None:
        """Create the virtual dataset of ``shape`` mapping row ``index`` of field ``name``.

        The source file is ".", the file that holds the view, so the file can be moved. A view
        of a row not yet written reads the source's fill value (0); the XDMF file names only
        views of written frames.
        """
        dcpl = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
        dcpl.set_fill_value(np.array(np.nan))
        source = h5py.h5s.create_simple((index + 1,) + shape)
        source.select_hyperslab((index,) + (0,) * len(shape), (1,) + shape)
        view = h5py.h5s.create_simple(shape)
        dcpl.set_virtual(view, b".", self._datasets[name].name.encode(), source)
        h5py.h5d.create(self._view_groups[name].id, f"{index:06d}".encode(), h5py.h5t.IEEE_F64LE,
                        view, dcpl=dcpl).close()

    def view(self, name: str, index: int) -> str:
        """HDF5 path of the virtual dataset showing frame ``index`` of field ``name``."""
        return f"/xdmf{self.path}/{name}/{index:06d}"


class _Mesh:
    """A body shown as one XDMF grid per frame: fixed topology and geometry, per-frame fields."""

    def __init__(self, name: str, topology_xml: str, geometry_xml: str, constant_xml: str,
                 series: _FrameSeries) -> None:
        self.name = name
        self.topology_xml = topology_xml
        self.geometry_xml = geometry_xml
        self.constant_xml = constant_xml
        self.series = series
        self.frames_xml: list[str] = []

    def add_frame_xml(self, h5name: str, index: int, time: float) -> None:
        """Build (once) the XDMF grid of frame ``index``."""
        assert self.series.fields is not None
        parts = [f'<Grid Name={quoteattr(self.name)} GridType="Uniform">'
                 f'<Time Value="{float(time)!r}"/>',
                 self.topology_xml, self.geometry_xml, self.constant_xml]
        for k, (centre, shape) in self.series.fields.items():
            full = (self.series.sizes[centre],) + shape
            parts.append(f'<Attribute Name={quoteattr(k)} '
                         f'AttributeType="{_ATTRIBUTE_TYPE[shape]}" Center="{centre}">'
                         f'{_data_item(h5name, self.series.view(k, index), full)}</Attribute>')
        parts.append("</Grid>")
        self.frames_xml.append("\n      ".join(parts))

    def xml(self) -> str:
        """The temporal collection of all frames so far."""
        head = (f'    <Grid Name={quoteattr(self.name)} GridType="Collection" '
                'CollectionType="Temporal">')
        body = "".join("\n      " + g for g in self.frames_xml)
        return head + body + "\n    </Grid>\n"


class _History:
    """Buffered per-step rows of a history: ``<group>/time`` (K,), ``<group>/<key>`` (K, ...).

    Rows reach the file in two phases: the key columns, then (after an HDF5 flush) the time
    column, which commits them. ``time`` is filled with NaN where unwritten, so a reader
    keeps the rows up to the first NaN time.
    """

    def __init__(self, file: h5py.File, path: str, values: Mapping[str, np.ndarray]) -> None:
        self.file = file
        self.path = path
        self.shapes = {k: v.shape for k, v in values.items()}
        self.buffers = {k: np.empty((HISTORY_BLOCK,) + s) for k, s in self.shapes.items()}
        self.times = np.empty(HISTORY_BLOCK)
        self.count = 0  # rows in the buffers
        self.written = 0  # rows committed to the file
        group = file.require_group(path)
        group.attrs["kind"] = "history"
        self.datasets = {
            k: group.create_dataset(k, shape=(0,) + s, maxshape=(None,) + s,
                                    chunks=(HISTORY_BLOCK,) + s, dtype=np.float64)
            for k, s in self.shapes.items()}
        self.time = group.create_dataset("time", shape=(0,), maxshape=(None,),
                                         chunks=(HISTORY_BLOCK,), dtype=np.float64,
                                         fillvalue=np.nan)

    @classmethod
    def resume(cls, file: h5py.File, path: str, rows: int) -> "_History":
        """Take over an existing history group (append mode), cut to its first ``rows`` rows."""
        group = file[path]
        h = cls.__new__(cls)
        h.file, h.path = file, path
        h.time = group["time"]
        if h.time.shape[0] < rows or np.isnan(h.time[:rows]).any():
            raise ValueError(f"history {path!r} holds fewer than the {rows} committed rows to "
                             "resume from")
        h.datasets = {k: ds for k, ds in group.items() if k != "time"}
        for ds in (*h.datasets.values(), h.time):
            ds.resize(rows, axis=0)
        h.shapes = {k: ds.shape[1:] for k, ds in h.datasets.items()}
        h.buffers = {k: np.empty((HISTORY_BLOCK,) + s) for k, s in h.shapes.items()}
        h.times = np.empty(HISTORY_BLOCK)
        h.count = 0
        h.written = rows
        return h

    def append(self, time: float, values: Mapping[str, Any]) -> None:
        if values.keys() != self.shapes.keys():
            raise ValueError(f"history {self.path!r}: keys are fixed by the first row "
                             f"{sorted(self.shapes)}, got {sorted(values)}")
        c = self.count
        for k, v in values.items():
            if np.shape(v) != self.shapes[k]:
                raise ValueError(f"history {self.path!r}: {k!r} has shape {np.shape(v)}, "
                                 f"expected {self.shapes[k]} as in the first row")
            self.buffers[k][c] = v
        self.times[c] = time
        self.count = c + 1
        if self.count == HISTORY_BLOCK:
            self.write_columns()
            self.file.flush()
            self.commit()

    def write_columns(self) -> None:
        """Phase 1: write the key columns of the buffered rows."""
        end = self.written + self.count
        for k, ds in self.datasets.items():
            if ds.shape[0] != end:
                ds.resize(end, axis=0)
                ds[self.written:end] = self.buffers[k][:self.count]

    def commit(self) -> None:
        """Phase 2, after a flush that followed :meth:`write_columns`: write the time column."""
        c = self.count
        if c:
            end = self.written + c
            self.time.resize(end, axis=0)
            self.time[self.written:end] = self.times[:c]
            self.written = end
            self.count = 0


def _refuse_if_being_written(path: Path) -> None:
    """Raise if another process holds ``path`` open for writing (its HDF5 file lock).

    HDF5 truncates a file before it finds the lock, so a second run would wipe a running
    run's results: look first, with a read-only open that the writer's lock refuses.
    """
    if not path.exists():
        return
    try:
        h5py.File(path, "r").close()
    except BlockingIOError as err:
        raise FileExistsError(f"results file {str(path)!r} is being written by another "
                              "process; choose another output path") from err
    except OSError:
        return  # not a readable HDF5 file: it is overwritten


class ResultsWriter:
    """Write a run's results (HDF5) frame by frame, keeping an XDMF file beside it up to date.

    Parameters
    ----------
    path
        The HDF5 file to create (overwritten if it exists), e.g. ``results/run.h5``. The XDMF
        file is the same path with suffix ``.xdmf``.
    case_text
        The case file (TOML text), stored as ``/meta`` attribute ``case``.
    meta
        Further ``/meta`` attributes (e.g. ranks, threads, title): strings, numbers or arrays.
        Ignored with ``append``.
    append
        Reopen an existing results file of the same case (``/meta`` case equal to
        ``case_text``) to continue a run from a checkpoint: register the same bodies again,
        then call :meth:`resume` before writing.

    Raises
    ------
    ValueError
        With ``append``, if the file holds another case.
    FileExistsError
        If another process is writing ``path`` (it holds the HDF5 file lock).

    Notes
    -----
    Units are SI throughout (see the module docstring for the layout). Use as a context
    manager, or call :meth:`close`. Bodies are added before the first frame; a frame is
    validated whole before anything of it is written, so a rejected frame leaves no trace.
    """

    def __init__(self, path: str | os.PathLike, case_text: str = "",
                 meta: dict | None = None, *, append: bool = False) -> None:
        self.path = Path(path)
        if self.path.suffix.lower() == ".xdmf":
            raise ValueError(f"results path {str(self.path)!r} must be the HDF5 file, "
                             "not the .xdmf")
        if ":" in self.path.name:
            raise ValueError(f"results file name {self.path.name!r} must not contain ':' "
                             "(XDMF separates file and dataset with ':')")
        self.xdmf_path = self.path.with_suffix(".xdmf")
        self._h5name = self.path.name
        self._meshes: dict[str, _Mesh] = {}
        self._histories: dict[str, _History] = {}
        self._frames = 0
        self._xdmf_frames = -1
        self._last_time = -np.inf
        self._append = append
        self._resumed = not append
        _refuse_if_being_written(self.path)
        if append:
            self._file: h5py.File | None = h5py.File(self.path, "r+")
            stored = _attr(self._file["meta"].attrs.get("case", ""))
            if stored != case_text:
                self._file.close()
                raise ValueError(f"results file {str(self.path)!r} was written by another case "
                                 "(its /meta case text differs); cannot append to it")
            return
        self._file = h5py.File(self.path, "w")
        m = self._file.create_group("meta")
        m.attrs["version"] = pdfem.__version__
        m.attrs["units"] = "SI"
        m.attrs["case"] = case_text
        m.attrs["created"] = datetime.now(timezone.utc).isoformat(timespec="seconds")
        for k, v in (meta or {}).items():
            try:
                m.attrs[k] = v
            except (TypeError, ValueError) as err:
                self._file.close()
                raise TypeError(f"meta item {k!r} = {v!r} cannot be stored as an HDF5 attribute "
                                "(use a string, a number or an array)") from err
        self._file.create_dataset("time", shape=(0,), maxshape=(None,), chunks=(HISTORY_BLOCK,),
                                  dtype=np.float64, fillvalue=np.nan)
        self._file.create_group("ice")
        self.flush()

    # -- setup ---------------------------------------------------------------------------

    @property
    def _h5(self) -> h5py.File:
        if self._file is None:
            raise ValueError(f"results file {str(self.path)!r} is closed")
        return self._file

    def _new_body(self, group: str, name: str) -> str:
        """Check a body name before registration; return its HDF5 path ``/<group>/<name>``."""
        _check_name(name, f"{group} name")
        if self._frames:
            raise ValueError(f"{group} {name!r} added after the first frame; add all bodies first")
        if f"{group}/{name}" in self._meshes:
            raise ValueError(f"{group} {name!r} is already registered")
        if self._append and f"/{group}/{name}" not in self._h5:
            raise ValueError(f"{group} {name!r} is not in the results file being appended to")
        return f"/{group}/{name}"

    def _points(self, what: str, x: np.ndarray) -> np.ndarray:
        x = np.ascontiguousarray(x, dtype=np.float64)
        if x.ndim != 2 or x.shape[1] != 3 or x.shape[0] == 0:
            raise ValueError(f"{what} has shape {x.shape}, expected (N, 3) with N > 0")
        return x

    def _geometry(self, path: str, n: int) -> str:
        return (f'<Geometry GeometryType="XYZ">'
                f'{_data_item(self._h5name, path, (n, 3))}</Geometry>')

    def add_ice_body(self, name: str, x0: np.ndarray, volume: np.ndarray | None = None,
                     index: np.ndarray | None = None) -> None:
        """Register an ice body and store its reference configuration.

        Parameters
        ----------
        name
            Body name (letters, digits, ``_ . + -``), the group ``/ice/<name>``.
        x0
            (N, 3) reference particle positions, m.
        volume
            (N,) particle volumes, m^3, optional; shown in ParaView as the field ``volume``.
        index
            (N,) global particle numbers, optional: the file then holds part of the body (one
            MPI rank's particles, :func:`read_results` puts the parts together).
        """
        f = self._h5
        path = self._new_body("ice", name)
        x0 = self._points(f"x0 of ice body {name!r}", x0)
        n = x0.shape[0]
        if volume is not None:
            volume = np.ascontiguousarray(volume, dtype=np.float64)
            if volume.shape != (n,):
                raise ValueError(f"volume of ice body {name!r} has shape {volume.shape}, "
                                 f"expected ({n},)")
        if self._append:
            if f[path]["x0"].shape != x0.shape:
                raise ValueError(f"ice body {name!r} has {n} particles, the results file "
                                 f"{f[path]['x0'].shape[0]}")
        else:
            g = f.create_group(path)
            g.attrs["kind"] = "ice_body"
            g.create_dataset("x0", data=x0)
            f.create_dataset(f"/xdmf{path}/vertices",
                             data=np.arange(n, dtype=np.int32).reshape(n, 1))
            if volume is not None:
                g.create_dataset("volume", data=volume)
            if index is not None:
                g.create_dataset("index", data=np.asarray(index, dtype=np.int64))
        constant = ""
        if volume is not None:
            constant = ('<Attribute Name="volume" AttributeType="Scalar" Center="Node">'
                        f'{_data_item(self._h5name, f"{path}/volume", (n,))}</Attribute>')
        vertices = _data_item(self._h5name, f"/xdmf{path}/vertices", (n, 1), "Int", 4)
        topology = (f'<Topology TopologyType="Polyvertex" NumberOfElements="{n}" '
                    f'NodesPerElement="1">{vertices}</Topology>')
        series = _FrameSeries(f, path, {"Node": n}, ((), (3,)), REQUIRED_ICE_FIELDS)
        self._meshes[f"ice/{name}"] = _Mesh(f"ice/{name}", topology,
                                            self._geometry(f"{path}/x0", n), constant, series)

    def add_structure(self, name: str, points: np.ndarray, cells: np.ndarray,
                      cell_type: str) -> None:
        """Register a structure (elastic mesh or rigid surface) and store its mesh.

        Parameters
        ----------
        name
            Structure name (letters, digits, ``_ . + -``), the group ``/structure/<name>``.
        points
            (Nn, 3) reference node positions, m.
        cells
            (Ne, k) connectivity into ``points`` in VTK / meshio node order.
        cell_type
            ``"tetra"``, ``"hexahedron"``, ``"triangle"`` (rigid surfaces) or ``"quad"``.
        """
        f = self._h5
        path = self._new_body("structure", name)
        points = self._points(f"points of structure {name!r}", points)
        if cell_type not in XDMF_TOPOLOGY:
            raise ValueError(f"cell_type {cell_type!r} of structure {name!r} is not one of "
                             f"{sorted(XDMF_TOPOLOGY)}")
        topology_type, k = XDMF_TOPOLOGY[cell_type]
        cells = np.ascontiguousarray(cells, dtype=np.int32)
        if cells.ndim != 2 or cells.shape[1] != k or cells.shape[0] == 0:
            raise ValueError(f"cells of structure {name!r} have shape {cells.shape}, expected "
                             f"(Ne, {k}) with Ne > 0 for {cell_type!r}")
        nn, ne = points.shape[0], cells.shape[0]
        if cells.min() < 0 or cells.max() >= nn:
            raise ValueError(f"cells of structure {name!r} index nodes outside 0..{nn - 1}")
        if self._append:
            if f[path]["points"].shape != points.shape or f[path]["cells"].shape != cells.shape:
                raise ValueError(f"structure {name!r} differs from the one in the results file")
        else:
            g = f.require_group("structure").create_group(name)
            g.attrs["kind"] = "structure"
            g.create_dataset("points", data=points)
            g.create_dataset("cells", data=cells).attrs["cell_type"] = cell_type
        topology = (f'<Topology TopologyType="{topology_type}" NumberOfElements="{ne}">'
                    f'{_data_item(self._h5name, f"{path}/cells", (ne, k), "Int", 4)}</Topology>')
        series = _FrameSeries(f, path, {"Node": nn, "Cell": ne}, ((), (3,)),
                              REQUIRED_STRUCTURE_FIELDS, CELL_FIELDS)
        self._meshes[f"structure/{name}"] = _Mesh(f"structure/{name}", topology,
                                                  self._geometry(f"{path}/points", nn), "", series)

    def resume(self, frames: int, history_rows: Mapping[str, int]) -> None:
        """Continue an appended file after its first ``frames`` frames (append mode only).

        Drops the frames after them and, of every history, the rows after its count in
        ``history_rows`` (histories not named there are deleted), rebuilds the XDMF file, and
        lets the run continue with :meth:`write_frame` and :meth:`append_history`. Call it
        once, after registering every body of the file again.

        Parameters
        ----------
        frames
            Frames to keep (>= 1).
        history_rows
            ``{history group: rows to keep}``, e.g. ``{"energy": 120, "loads/panel": 1200}``.
        """
        if not self._append or self._resumed:
            raise ValueError("resume() is for a writer opened with append=True, once")
        f = self._h5
        registered = {f"{g}/{n}" for g in ("ice", "structure") for n in f.get(g, {})}
        if registered != set(self._meshes):
            raise ValueError(f"register every body of the results file first: the file has "
                             f"{sorted(registered)}, registered {sorted(self._meshes)}")
        times = f["time"]
        if frames < 1 or times.shape[0] < frames or np.isnan(times[:frames]).any():
            raise ValueError(f"the results file holds fewer than the {frames} frames to "
                             "resume from")
        times.resize(frames, axis=0)
        kept = times[:frames]
        for mesh in self._meshes.values():
            mesh.series.resume(frames)
            if mesh.series.fields is not None:
                for i, t in enumerate(kept):
                    mesh.add_frame_xml(self._h5name, i, float(t))
        stack = [(k, g) for k, g in f.items() if k not in _RESERVED and isinstance(g, h5py.Group)]
        while stack:
            name, g = stack.pop()
            if _attr(g.attrs.get("kind")) == "history":
                if name in history_rows:
                    self._histories[name] = _History.resume(f, "/" + name, int(history_rows[name]))
                else:
                    del f[name]
            else:
                stack.extend((f"{name}/{k}", s) for k, s in g.items() if isinstance(s, h5py.Group))
        self._frames = frames
        self._last_time = float(kept[-1])
        self._resumed = True
        self._xdmf_frames = -1
        self.flush()

    def history_rows(self) -> dict[str, int]:
        """``{history group: rows appended so far}`` (committed or buffered), for a checkpoint."""
        return {g: h.written + h.count for g, h in self._histories.items()}

    # -- per output time -----------------------------------------------------------------

    def write_frame(self, time: float, ice: Mapping[str, Mapping[str, np.ndarray]],
                    structures: Mapping[str, Mapping[str, np.ndarray]] | None = None) -> int:
        """Append one output frame, flush the file and rewrite the XDMF file.

        Parameters
        ----------
        time
            Output time, s; strictly greater than the previous frame's.
        ice
            For every registered ice body, its fields: at least ``u`` (N, 3) displacement in m,
            ``v`` (N, 3) velocity in m/s and ``damage`` (N,); any further (N,) or (N, 3)
            field. The field set of a body is fixed by the first frame.
        structures
            For every registered structure, its fields: at least ``u`` (Nn, 3) nodal
            displacement in m; ``von_mises`` (Ne,) in Pa and other names in
            :data:`CELL_FIELDS` are per element, any other (Nn,) or (Nn, 3) field per node.

        Returns
        -------
        int
            The index of the frame written.
        """
        self._h5  # raises if the file is closed
        if not self._resumed:
            raise ValueError("a writer opened with append=True needs resume() before writing")
        time = float(time)
        if not np.isfinite(time) or time <= self._last_time:
            raise ValueError(f"frame time {time!r} must be finite and greater than the "
                             f"previous frame time {self._last_time!r}")
        bodies = {f"ice/{k}": v for k, v in ice.items()}
        bodies.update({f"structure/{k}": v for k, v in (structures or {}).items()})
        if bodies.keys() != self._meshes.keys():
            raise ValueError("write_frame needs every registered body "
                             f"{sorted(self._meshes)}, got {sorted(bodies)}")
        checked = {k: self._meshes[k].series.check(v) for k, v in bodies.items()}
        index = self._frames
        for k, arrays in checked.items():
            self._meshes[k].series.append(index, arrays)
        self._sync(time)
        for mesh in self._meshes.values():
            mesh.add_frame_xml(self._h5name, index, time)
        self._update_xdmf()
        return index

    def append_history(self, group: str, time: float,
                       values: dict[str, float | np.ndarray]) -> None:
        """Append one row to a per-step history (buffered; written in blocks).

        Parameters
        ----------
        group
            History group, e.g. ``"energy"`` or ``"loads/<name>"`` (components are names of
            letters, digits, ``_ . + -``; the first must not be meta, time, ice, structure, xdmf).
        time
            Time of the row, s.
        values
            Scalars or arrays (e.g. ``force`` (3,) in N); keys and shapes fixed by the first row.
        """
        f = self._h5
        if not self._resumed:
            raise ValueError("a writer opened with append=True needs resume() before writing")
        h = self._histories.get(group)
        if h is None:
            parts = group.split("/") if isinstance(group, str) else [group]
            for p in parts:
                _check_name(p, "history group component")
            if parts[0] in _RESERVED:
                raise ValueError(f"history group {group!r} would collide with /{parts[0]}")
            first = {_check_name(k, "history key"): np.asarray(v, dtype=np.float64)
                     for k, v in values.items()}
            clash = [g for g in self._histories
                     if g.startswith(group + "/") or group.startswith(g + "/")]
            if clash:
                raise ValueError(f"history group {group!r} would nest with history {clash[0]!r}")
            if "time" in first:
                raise ValueError(f"history {group!r}: 'time' is not allowed as a key")
            h = _History(f, "/" + group, first)
            self._histories[group] = h
        h.append(time, values)

    # -- file state ----------------------------------------------------------------------

    def flush(self) -> None:
        """Write buffered history rows, flush the HDF5 file and bring the XDMF file up to date."""
        self._sync()
        self._update_xdmf()

    def _sync(self, frame_time: float | None = None) -> None:
        """Flush in steps, so that what is on disk is always a committed prefix.

        1. history key columns (frame fields are already written), flush;
        2. history time rows, which commit the history rows, flush;
        3. for a new frame, its ``/time`` row, which commits the frame, flush.
        A time row on disk thus implies its data is on disk, and a committed frame implies
        every history row appended before it is committed. Unwritten time rows read NaN.
        """
        f = self._h5
        for h in self._histories.values():
            h.write_columns()
        f.flush()
        for h in self._histories.values():
            h.commit()
        f.flush()
        if frame_time is not None:
            ds = f["time"]
            ds.resize(self._frames + 1, axis=0)
            ds[self._frames] = frame_time
            self._frames += 1
            self._last_time = frame_time
            f.flush()

    def _update_xdmf(self) -> None:
        if self._xdmf_frames != self._frames:
            self._write_xdmf()
            self._xdmf_frames = self._frames

    def _write_xdmf(self) -> None:
        text = ('<?xml version="1.0" encoding="utf-8"?>\n'
                '<Xdmf Version="3.0">\n  <Domain>\n'
                + "".join(m.xml() for m in self._meshes.values() if m.frames_xml)
                + "  </Domain>\n</Xdmf>\n")
        tmp = self.xdmf_path.with_name(self.xdmf_path.name + ".tmp")
        tmp.write_text(text, encoding="utf-8")
        os.replace(tmp, self.xdmf_path)

    def close(self) -> None:
        """Write what is buffered and close the file (closing twice is allowed)."""
        if self._file is not None:
            try:
                for mesh in self._meshes.values():
                    mesh.series.drop_unused_views(self._frames)
                self.flush()
            finally:
                self._file.close()
                self._file = None

    @property
    def n_frames(self) -> int:
        """Number of frames written."""
        return self._frames

    def __enter__(self) -> ResultsWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _attr(v: Any) -> Any:
    if isinstance(v, bytes):
        return v.decode()
    if isinstance(v, np.generic):
        return v.item()
    return v


def _readable_prefix(ds: h5py.Dataset, n: int) -> np.ndarray:
    """Rows ``[:m]`` of ``ds`` for the largest ``m <= n`` that reads without error.

    A run killed while flushing can leave the last rows' chunks past the file's recorded end;
    those rows raise ``OSError``. Rows are dropped a chunk at a time from the end.
    """
    step = ds.chunks[0] if ds.chunks else n
    m = n
    while m > 0:
        try:
            return ds[:m]
        except OSError:
            m = (m - 1) // step * step
    return ds[:0]


def _committed(time: np.ndarray) -> np.ndarray:
    """The rows of a time column before its first NaN (unwritten rows read NaN)."""
    bad = np.flatnonzero(np.isnan(time))
    return time[:bad[0]] if bad.size else time


def read_results(path: str | os.PathLike) -> dict:
    """Load a results file into numpy arrays.

    Parameters
    ----------
    path
        The HDF5 results file. It may come from a killed run, or still be open in a running
        writer (a file locked by another process is then read without HDF5 file locking).

    Returns
    -------
    dict
        ``{"meta": {attr: value}, "time": (F,), "ice": {body: {"x0", "volume"?, "u", "v",
        "damage", ...}}, "structure": {name: {"points", "cells", "cell_type", "u",
        "von_mises"?, ...}}, "histories": {group: {"time": (K,), key: (K, ...)}}}``. Only
        committed rows are returned: F counts the rows of ``/time`` before the first NaN (a
        time row is written only after its frame's data was flushed), cut further to the
        frames that every field dataset can read; each history likewise (a run killed while
        writing may have extended some datasets and not others).
    """
    out: dict[str, Any] = {"meta": {}, "time": None, "ice": {}, "structure": {},
                           "histories": {}}
    constant = {"x0", "volume", "index", "points", "cells"}
    try:
        f = h5py.File(path, "r")
    except BlockingIOError:
        f = h5py.File(path, "r", locking=False)
    with f:
        out["meta"] = {k: _attr(v) for k, v in f["meta"].attrs.items()}
        frames = {"time": _committed(_readable_prefix(f["time"], f["time"].shape[0]))}
        n = frames["time"].shape[0]
        for group in ("ice", "structure"):
            for name, g in f.get(group, {}).items():
                body = out[group].setdefault(name, {})
                for k, ds in g.items():
                    if k in constant:
                        body[k] = ds[()]
                        if k == "cells":
                            body["cell_type"] = _attr(ds.attrs["cell_type"])
                    else:
                        frames[f"{group}/{name}/{k}"] = a = _readable_prefix(ds, min(n, ds.shape[0]))
                        n = min(n, a.shape[0])
        out["time"] = frames.pop("time")[:n]
        for key, a in frames.items():
            group, name, k = key.split("/")
            out[group][name][k] = a[:n]
        stack = [(k, g) for k, g in f.items() if k not in _RESERVED and isinstance(g, h5py.Group)]
        while stack:
            name, g = stack.pop()
            if _attr(g.attrs.get("kind")) == "history":
                rows = {k: _readable_prefix(ds, ds.shape[0]) for k, ds in g.items()}
                rows["time"] = _committed(rows["time"])
                k_min = min(a.shape[0] for a in rows.values())
                out["histories"][name] = {k: a[:k_min] for k, a in rows.items()}
            else:
                stack.extend((f"{name}/{k}", s) for k, s in g.items() if isinstance(s, h5py.Group))
    ranks = int(out["meta"].get("ice_per_rank", 0))
    if ranks:
        _merge_rank_files(out, [rank_file(path, r) for r in range(ranks)])
    return out


def rank_file(path: str | os.PathLike, rank: int) -> Path:
    """The per-rank ice file of MPI rank ``rank`` beside a results file:
    ``results.h5`` -> ``results.rank<rank>.h5``."""
    p = Path(path)
    return p.with_name(f"{p.stem}.rank{rank}{p.suffix}")


def _merge_rank_files(out: dict, files: list[Path]) -> None:
    """Put the ice of per-rank files (``run.output_per_rank``) into ``out`` in global particle
    order, keeping the frames that every file holds."""
    parts = []
    for file in files:
        if not file.is_file():
            raise FileNotFoundError(f"{file}: the per-rank ice file of this results file is "
                                    "missing (keep the results.rank*.h5 files beside it)")
        parts.append(read_results(file))
    n = min([out["time"].shape[0]] + [p["time"].shape[0] for p in parts])
    out["time"] = out["time"][:n]
    for name in parts[0]["ice"]:
        pieces = [p["ice"][name] for p in parts]
        order = np.concatenate([q["index"] for q in pieces])
        body = {}
        for k in pieces[0]:
            if k == "index":
                continue
            frame_axis = k not in ("x0", "volume")
            a = np.concatenate([q[k][:n] if frame_axis else q[k] for q in pieces],
                               axis=1 if frame_axis else 0)
            merged = np.empty_like(a)
            if frame_axis:
                merged[:, order] = a
            else:
                merged[order] = a
            body[k] = merged
        out["ice"][name] = body
    for name, body in out["structure"].items():
        for k, a in body.items():
            if k not in ("points", "cells", "cell_type"):
                body[k] = a[:n]
