"""The results writer of a run: HDF5 written frame by frame, an XDMF file beside it for ParaView.

The time loop creates one :class:`ResultsWriter`, registers the ice bodies and structures,
then calls :meth:`ResultsWriter.write_frame` at every output time and
:meth:`ResultsWriter.append_history` at every step. The file layout is described in
:mod:`pdfem.output.layout`, the XDMF file in :mod:`pdfem.output.xdmf_grids`.

Robustness: the file stays open (HDF5's default, oldest file format) and every frame is
committed in steps, each ended by a flush: its fields and the pending history columns; the
histories' time rows; its ``/time`` row. Then the frame is added to the XDMF file in place
(:class:`pdfem.output.xdmf_file.XdmfFile`: well-formed after every write, rewritten atomically
when its reserve runs out), at a cost per frame that does not grow with the run. Time datasets read NaN where unwritten, so a finite time
row means its data reached the file, and a committed frame means every history row appended
before it did too.
A process killed after :meth:`~ResultsWriter.write_frame` returns leaves a pair that h5py,
meshio and ParaView read, with every frame so far; one killed inside it may lose that frame,
and :func:`pdfem.output.reader.read_results` returns only committed rows that read back. Not
used, by measurement: ``libver="latest"`` (a killed writer leaves the file marked open for
writing and HDF5 refuses to open it without ``h5clear``) and SWMR (no new objects may be
created once it starts, but views and histories are added as the run goes). Neither file is
fsync'ed: this protects against the death of the process, not of the machine. While it is
written the file holds HDF5's lock, and a second :class:`ResultsWriter` on it is refused (HDF5
itself would truncate it first); to read it during a run, start the reader (e.g. ParaView)
with ``HDF5_USE_FILE_LOCKING=FALSE`` (``read_results`` does this itself).

Write errors (no space left, a file-size limit, a quota, an I/O error): before every write that
can grow the file, room for it is reserved on disk (:class:`pdfem.output.room.Room`), so a write
that would not fit fails before HDF5 touches the file, which keeps every frame flushed before.
The failure raises :class:`pdfem.errors.OutputError` (the message says what failed, why, and
what the file holds); the writer then never writes to the file again, and :meth:`close`
releases it without a write (:func:`pdfem.output.room.release`). Measured: without the
reserve, HDF5's failed flush leaves a file that no longer opens, and closing it crashes the
process (:mod:`pdfem.output.room`).

Restart: ``ResultsWriter(path, case_text, append=True)`` reopens the file of a run (killed or
not) of the same case; after the bodies are registered again, :meth:`ResultsWriter.resume`
cuts every frame dataset and history back to the counts a checkpoint recorded (frames and
rows written after it are dropped, as are their XDMF views), rewrites the XDMF file, and the
run continues appending as before.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np

from pdfem.errors import OutputError
from pdfem.output import xdmf, xdmf_grids
from pdfem.output.bodies import store_ice_body, store_structure
from pdfem.output.datasets import growing_dataset, has_committed, put_rows
from pdfem.output.files import bound_metadata_cache, refuse_if_being_written
from pdfem.output.frames import VIEW_BATCH, FrameSeries, frames_per_chunk
from pdfem.output.histories import HISTORY_BLOCK, History, first_row
from pdfem.output.layout import (CELL_FIELDS, REQUIRED_ICE_FIELDS, REQUIRED_STRUCTURE_FIELDS,
                                 attr_value, check_name, history_groups, write_meta)
from pdfem.output.room import NoRoom, Room, failure, release
from pdfem.output.xdmf_file import XdmfFile

VIEW_BYTES = 512
"""Bytes an XDMF view of one field and frame takes in the file (measured: 170 to 350; the
reserve's margin holds more)."""


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
    expected_frames
        Frames the run expects to write, or 0: the XDMF file reserves room for them at once
        (:class:`pdfem.output.xdmf_file.XdmfFile`), so its cost per frame stays the same all run.

    Raises
    ------
    ValueError
        With ``append``, if the file holds another case.
    FileExistsError
        If another process is writing ``path`` (it holds the HDF5 file lock).
    OutputError
        If the new file cannot be written (no space, a file-size limit, an I/O error); so
        may every method that writes.

    Notes
    -----
    Units are SI throughout (see :mod:`pdfem.output.layout` for the layout). Use as a context
    manager, or call :meth:`close`. Bodies are added before the first frame; a frame is
    validated whole before anything of it is written, so a rejected frame leaves no trace.
    """

    def __init__(self, path: str | os.PathLike, case_text: str = "",
                 meta: dict | None = None, *, append: bool = False,
                 expected_frames: int = 0) -> None:
        self.path = Path(path)
        if self.path.suffix.lower() == ".xdmf":
            raise ValueError(f"results path {str(self.path)!r} must be the HDF5 file, "
                             "not the .xdmf")
        if ":" in self.path.name:
            raise ValueError(f"results file name {self.path.name!r} must not contain ':' "
                             "(XDMF separates file and dataset with ':')")
        self.xdmf_path = self.path.with_suffix(".xdmf")
        self._h5name = self.path.name
        self._grids: dict[str, xdmf_grids.BodyGrid] = {}
        self._rank_grids: list[xdmf_grids.BodyGrid] = []  # ice in per-rank files (XDMF only)
        self._xdmf = XdmfFile(self.xdmf_path, expected_frames)
        self._histories: dict[str, History] = {}
        self._frames = 0
        self._last_time = -np.inf
        self._append = append
        self._resumed = not append
        self._room = Room(self.path)
        self._need = 0            # bytes the write under way may add (for the reserve)
        self._failure = ""        # the message of a failed write: nothing is written after it
        self._file: h5py.File | None = None
        refuse_if_being_written(self.path)
        if append:
            self._file = h5py.File(self.path, "r+")
            self._flushed = self._file.id.get_filesize()  # bytes up to the last flush
            bound_metadata_cache(self._file)
            stored = attr_value(self._file["meta"].attrs.get("case", ""))
            if stored != case_text:
                self._file.close()
                raise ValueError(f"results file {str(self.path)!r} was written by another case "
                                 "(its /meta case text differs); cannot append to it")
            return
        try:
            self._file = h5py.File(self.path, "w")
        except OSError as exc:
            raise OutputError(failure("a new results file", self.path, exc,
                                      "Nothing was written.")) from None
        self._flushed = 0
        bound_metadata_cache(self._file)
        try:
            with self._writing("the run's metadata", len(case_text)):
                write_meta(self._file, case_text, meta or {})
                growing_dataset(self._file, "time", (), HISTORY_BLOCK, fillvalue=np.nan)
                self._file.create_group("ice")
                self._sync()
        except (TypeError, OutputError):
            self.close()
            raise
        self._xdmf_write(self._xdmf.rewrite)

    # -- setup ---------------------------------------------------------------------------

    @property
    def _h5(self) -> h5py.File:
        if self._file is None:
            raise ValueError(f"results file {str(self.path)!r} is closed")
        return self._file

    def _new_body(self, group: str, name: str) -> str:
        """Check a body name before registration; return its HDF5 path ``/<group>/<name>``."""
        check_name(name, f"{group} name")
        if self._frames:
            raise ValueError(f"{group} {name!r} added after the first frame; add all bodies first")
        if f"{group}/{name}" in self._grids:
            raise ValueError(f"{group} {name!r} is already registered")
        if self._append and f"/{group}/{name}" not in self._h5:
            raise ValueError(f"{group} {name!r} is not in the results file being appended to")
        return f"/{group}/{name}"

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
            MPI rank's particles, :func:`~pdfem.output.reader.read_results` puts the parts
            together).
        """
        path = self._new_body("ice", name)
        data = sum(np.asarray(a).nbytes for a in (x0, volume, index) if a is not None)
        with self._writing(f"ice body {name!r}", 2 * data) as f:
            n = store_ice_body(f, path, x0, volume, index, self._append)
            if not self._append:
                xdmf.write_vertices(f, path, n)
        self._grids[f"ice/{name}"] = xdmf_grids.ice_grid(
            self._h5name, f"ice/{name}", path, n, volume is not None,
            FrameSeries(f, path, {"Node": n}, ((), (3,)), REQUIRED_ICE_FIELDS,
                        positions=np.ascontiguousarray(x0, dtype=np.float64)))

    def add_rank_ice_body(self, name: str, files: list[tuple[str, int]], volume: bool) -> None:
        """Show an ice body that the MPI ranks write to their own files (``run.output_per_rank``)
        in this file's XDMF: each frame shows the ranks' grids, each from its own file
        (:func:`pdfem.output.xdmf_grids.rank_ice_grid`). Nothing is stored in the HDF5 file.

        Parameters
        ----------
        name
            Body name.
        files
            ``(per-rank file name relative to this file, particles in it)`` of every rank.
        volume
            Whether the per-rank files hold the particle volumes.
        """
        if self._frames:
            raise ValueError(f"ice {name!r} added after the first frame; add all bodies first")
        self._rank_grids.append(xdmf_grids.rank_ice_grid(f"ice/{name}", f"/ice/{name}",
                                                         list(files), volume))

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
        path = self._new_body("structure", name)
        with self._writing(f"structure {name!r}",
                           2 * (np.asarray(points).nbytes + np.asarray(cells).nbytes)) as f:
            nn, ne = store_structure(f, path, points, cells, cell_type, self._append)
        series = FrameSeries(f, path, {"Node": nn, "Cell": ne}, ((), (3,)),
                             REQUIRED_STRUCTURE_FIELDS, CELL_FIELDS,
                             np.ascontiguousarray(points, dtype=np.float64))
        self._grids[f"structure/{name}"] = xdmf_grids.structure_grid(
            self._h5name, f"structure/{name}", path, cell_type, nn, ne, series)

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
        if registered != set(self._grids):
            raise ValueError(f"register every body of the results file first: the file has "
                             f"{sorted(registered)}, registered {sorted(self._grids)}")
        times = f["time"]
        if frames < 1 or not has_committed(times, frames):
            raise ValueError(f"the results file holds fewer than the {frames} frames to "
                             "resume from")
        with self._writing(f"the results file cut back to frame {frames}"):
            times.resize(frames, axis=0)
            kept = times[:frames]
            for grid in self._grids.values():
                grid.series.resume(frames)
            for name, _ in history_groups(f):
                if name in history_rows:
                    self._histories[name] = History.resume(f, "/" + name,
                                                           int(history_rows[name]))
                else:
                    del f[name]
            self._frames = frames
            self._last_time = float(kept[-1])
            self._resumed = True
            self._sync()
        self._set_xdmf_grids([g for g in self._grids.values() if g.series.fields is not None])
        self._xdmf_write(self._xdmf.set_times, kept)

    def history_rows(self) -> dict[str, int]:
        """``{history group: rows appended so far}`` (committed or buffered), for a checkpoint."""
        return {g: h.rows for g, h in self._histories.items()}

    def _set_xdmf_grids(self, grids: list[xdmf_grids.BodyGrid]) -> None:
        """Show the per-rank ice and ``grids`` in the XDMF file, every field on every grid."""
        grids = self._rank_grids + grids
        with self._writing("the empty fields the ParaView index names"):
            xdmf_grids.pad(grids, self._h5, self._h5name)
            self._h5.flush()  # the NaN datasets the XDMF file is about to name
        self._xdmf.grids = grids

    # -- per output time -----------------------------------------------------------------

    def _check_writable(self) -> h5py.File:
        f = self._h5  # raises if the file is closed
        if not self._resumed:
            raise ValueError("a writer opened with append=True needs resume() before writing")
        return f

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
            :data:`~pdfem.output.layout.CELL_FIELDS` are per element, any other (Nn,) or
            (Nn, 3) field per node.

        Returns
        -------
        int
            The index of the frame written.
        """
        self._check_writable()
        time = float(time)
        if not np.isfinite(time) or time <= self._last_time:
            raise ValueError(f"frame time {time!r} must be finite and greater than the "
                             f"previous frame time {self._last_time!r}")
        bodies = {f"ice/{k}": v for k, v in ice.items()}
        bodies.update({f"structure/{k}": v for k, v in (structures or {}).items()})
        if bodies.keys() != self._grids.keys():
            raise ValueError("write_frame needs every registered body "
                             f"{sorted(self._grids)}, got {sorted(bodies)}")
        checked = {k: self._grids[k].series.check(v) for k, v in bodies.items()}
        index = self._frames
        with self._writing(f"frame {index} (t = {time:.6e} s)", self._frame_bytes(checked)):
            for k, arrays in checked.items():
                self._grids[k].series.append(index, arrays)
            self._sync(time)
        if index == 0:
            self._set_xdmf_grids(list(self._grids.values()))
        self._xdmf_write(self._xdmf.add_frame, time)
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
        f = self._check_writable()
        h = self._histories.get(group)
        if h is None:
            row = first_row(group, values, self._histories)
            with self._writing(f"the new history {group!r}"):
                h = History.create(f, "/" + group, row)
            self._histories[group] = h
        if h.append(time, values):
            with self._writing(f"a block of rows of the history {group!r}"):
                h.write_block()

    # -- file state ----------------------------------------------------------------------

    def flush(self) -> None:
        """Write buffered history rows and flush the HDF5 file (the XDMF file is always up to
        date: every frame is added to it as it is written)."""
        with self._writing("the buffered history rows"):
            self._sync()

    @contextmanager
    def _writing(self, what: str, nbytes: int = 0) -> Iterator[h5py.File]:
        """Reserve room for a write of ``what`` (``nbytes`` of data, plus a block of every
        history and the margin), run it, and turn a failure into :class:`OutputError`.

        Raises
        ------
        OutputError
            No room for the write (the file is untouched), or HDF5 failed writing it (the
            file may be damaged past its last frame), or an earlier write failed.
        """
        if self._failure:
            raise OutputError(self._failure)
        f = self._h5
        self._need = int(nbytes) + sum(h.new_bytes for h in self._histories.values())
        try:
            self._room.ensure(f, self._need)
            yield f
        except NoRoom as exc:  # before HDF5 wrote past the file's end: the file is whole
            raise self._fail(what, exc, "") from None
        except (OSError, RuntimeError) as exc:
            raise self._fail(what, exc, " HDF5 failed part-way through this write, so the "
                             "file may not open.") from None
        self._room.observe(f)

    def _fail(self, what: str, exc: BaseException, note: str) -> OutputError:
        """Remember a failed write (nothing is written after it) and make its error."""
        n = self._frames
        frames = (f"the {n} frame{'s' if n > 1 else ''} written before (to t = "
                  f"{self._last_time:.6e} s)" if n else "no frame yet")
        kept = (f"{self.path.name} keeps {frames}, {self._flushed:,} bytes, and reads with "
                "h5py and pdfem post" if self._flushed else f"{self.path.name} holds nothing")
        self._failure = failure(what, self.path, exc, (
            f"{kept}; nothing more is written to it.{note} Free space (or raise the limit), "
            "then run again, or continue from the run's checkpoint with --restart if it wrote "
            "one."))
        return OutputError(self._failure)

    def _frame_bytes(self, checked: Mapping[str, Mapping[str, np.ndarray]]) -> int:
        """Bytes the next frame (fields ``checked`` by body) adds to the file: a chunk of every
        field that starts one and, when a batch of views is due, the views."""
        index, total = self._frames, 0
        for body, arrays in checked.items():
            views = self._grids[body].series.views_due(index)
            for a in arrays.values():
                frames = frames_per_chunk(a.shape)
                total += frames * a.nbytes if index % frames == 0 else 0
                total += VIEW_BATCH * VIEW_BYTES if views else 0
        return total

    def _xdmf_write(self, write, *args) -> None:
        """Run a write of the XDMF file; its failure is an :class:`OutputError` (the HDF5 file
        is unharmed)."""
        try:
            write(*args)
        except OSError as exc:
            self._failure = failure("the ParaView index", self.xdmf_path, exc, (
                f"{self.path.name} keeps its {self._frames} frame(s) and reads with h5py and "
                "pdfem post; nothing more is written."))
            raise OutputError(self._failure) from None

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
        self._flush(f)
        for h in self._histories.values():
            h.commit()
        self._flush(f)
        if frame_time is not None:
            put_rows(f["time"], self._frames, np.array([frame_time]))
            self._frames += 1
            self._last_time = frame_time
            self._flush(f)

    def _flush(self, f: h5py.File) -> None:
        """Flush ``f`` with the room of the write under way reserved again (HDF5 may have cut
        the file back to its end)."""
        self._room.keep(f)
        f.flush()
        self._flushed = f.id.get_filesize()

    def close(self) -> None:
        """Write what is buffered and close the file (closing twice is allowed); after a failed
        write, release it without writing (:func:`pdfem.output.room.release`)."""
        if self._file is None:
            return
        try:
            if not self._failure:
                with self._writing("the last history rows"):
                    for grid in self._grids.values():
                        grid.series.drop_unused_views(self._frames)
                    self._sync()
        finally:
            f, self._file = self._file, None
            if self._failure:
                release(f)
                self._room.trim(self._flushed)
            else:
                end = f.id.get_filesize()  # closing only shrinks the file's end
                f.close()
                self._room.trim(end)

    @property
    def n_frames(self) -> int:
        """Number of frames written."""
        return self._frames

    def __enter__(self) -> ResultsWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
