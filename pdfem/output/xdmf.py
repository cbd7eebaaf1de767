"""The XDMF file beside a results file, for ParaView: per-frame grids over HDF5 views.

``<stem>.xdmf`` (XDMF 3) has one temporal collection per body; each frame is a uniform grid:
for an ice body Polyvertex topology over its particles and geometry ``x0``, for a structure
its elements (Tetrahedron, Hexahedron, Triangle, Quadrilateral, Tetrahedron_10 or
Hexahedron_20) and geometry ``points``;
one attribute per field (Scalar or Vector, centred on the nodes or, for fields such as
``von_mises``, on the cells). The HDF5 file is named relative to the XDMF file, so the two
can be moved together. An ice body that an MPI run wrote in per-rank files is one spatial
collection per frame of the ranks' grids, each naming its own file (:class:`RankIceGrid`).
Each attribute references a per-frame dataset
``/xdmf/ice/<body>/<field>/<frame>``: an HDF5 virtual dataset that maps frame F of the
(F, N, ...) dataset (no copy, :func:`create_view`). meshio's ``TimeSeriesReader`` cannot
read XDMF hyperslabs; it and VTK's ``vtkXdmfReader`` (ParaView's XDMF reader) both read
these views.

Constant cost per frame (:class:`XdmfFile`): each temporal collection is followed on disk by a
run of spaces (a reserve); a new frame's grid is written over the start of each collection's
reserve, in place, one ``write`` per collection, so the file is well-formed XML before and
after each write. When a reserve runs out the whole file is written again (atomically, through
a temporary file and ``os.replace``) with every reserve as large as its collection's text so
far: the rewrites come at geometrically spaced frames, so the cost per frame is O(1) amortized
and O(1) outside the rewrite frames (measured in ``benchmarks/output_frames.py``).
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path
from typing import Protocol
from xml.sax.saxutils import escape, quoteattr

import h5py
import numpy as np

class Series(Protocol):
    """What a grid of frames reads from the frame series it shows
    (:class:`pdfem.output.frames.FrameSeries`): its HDF5 ``path``, its ``fields`` (name ->
    (centre, shape per entity)) and the entity count per centre ``sizes``."""

    path: str
    fields: dict | None
    sizes: dict

XDMF_TOPOLOGY = {"tetra": ("Tetrahedron", 4), "hexahedron": ("Hexahedron", 8),
                 "triangle": ("Triangle", 3), "quad": ("Quadrilateral", 4),
                 # quadratic cells, XDMF TopologyType names (xdmf.org, "XDMF Model and Format"),
                 # node order as meshio / VTK (corners, then edge midpoints)
                 "tetra10": ("Tetrahedron_10", 10), "hexahedron20": ("Hexahedron_20", 20)}
"""meshio cell type -> (XDMF topology type, nodes per cell); node order as in VTK."""

_ATTRIBUTE_TYPE = {(): "Scalar", (3,): "Vector"}


def _dims(shape: tuple[int, ...]) -> str:
    return " ".join(str(int(n)) for n in shape)


def data_item(h5name: str, path: str, shape: tuple[int, ...], number_type: str = "Float",
              precision: int = 8) -> str:
    """XDMF DataItem referencing the whole HDF5 dataset ``path`` of file ``h5name``."""
    return (f'<DataItem Dimensions="{_dims(shape)}" NumberType="{number_type}" '
            f'Precision="{precision}" Format="HDF">{escape(h5name)}:{escape(path)}</DataItem>')


def attribute(name: str, shape: tuple[int, ...], centre: str, item: str) -> str:
    """XDMF Attribute ``name`` (items of ``shape`` () or (3,), centred on "Node" or "Cell")."""
    return (f'<Attribute Name={quoteattr(name)} AttributeType="{_ATTRIBUTE_TYPE[shape]}" '
            f'Center="{centre}">{item}</Attribute>')


def geometry(h5name: str, path: str, n: int) -> str:
    """XDMF Geometry of the (n, 3) positions in dataset ``path``."""
    return f'<Geometry GeometryType="XYZ">{data_item(h5name, path, (n, 3))}</Geometry>'


def polyvertex_topology(h5name: str, body: str, n: int) -> str:
    """XDMF Topology of ``n`` particles, one vertex each, of the body at HDF5 path ``body``.

    It references ``/xdmf<body>/vertices``, made by :func:`write_vertices`.
    """
    vertices = data_item(h5name, f"/xdmf{body}/vertices", (n, 1), "Int", 4)
    return (f'<Topology TopologyType="Polyvertex" NumberOfElements="{n}" '
            f'NodesPerElement="1">{vertices}</Topology>')


def write_vertices(file: h5py.File, body: str, n: int) -> None:
    """Store ``/xdmf<body>/vertices`` (n, 1) int32 0 .. n - 1 for :func:`polyvertex_topology`."""
    file.create_dataset(f"/xdmf{body}/vertices", data=np.arange(n, dtype=np.int32).reshape(n, 1))


def cell_topology(h5name: str, cells: str, cell_type: str, ne: int) -> str:
    """XDMF Topology of ``ne`` elements of ``cell_type`` whose connectivity is dataset ``cells``."""
    topology_type, k = XDMF_TOPOLOGY[cell_type]
    return (f'<Topology TopologyType="{topology_type}" NumberOfElements="{ne}">'
            f'{data_item(h5name, cells, (ne, k), "Int", 4)}</Topology>')


def view_path(body: str, field: str, index: int) -> str:
    """HDF5 path of the virtual dataset showing frame ``index`` of ``<body>/<field>``."""
    return f"/xdmf{body}/{field}/{index:06d}"


def create_view(group: h5py.Group, source: h5py.Dataset, index: int,
                shape: tuple[int, ...]) -> None:
    """Create in ``group`` the virtual dataset ``<index:06d>`` mapping row ``index`` of ``source``.

    The source file is ".", the file that holds the view, so the file can be moved. A view
    of a row not yet written reads the source's fill value (0); the XDMF file names only
    views of written frames.
    """
    dcpl = h5py.h5p.create(h5py.h5p.DATASET_CREATE)
    dcpl.set_fill_value(np.array(np.nan))
    space = h5py.h5s.create_simple((index + 1,) + shape)
    space.select_hyperslab((index,) + (0,) * len(shape), (1,) + shape)
    view = h5py.h5s.create_simple(shape)
    dcpl.set_virtual(view, b".", source.name.encode(), space)
    h5py.h5d.create(group.id, f"{index:06d}".encode(), h5py.h5t.IEEE_F64LE,
                    view, dcpl=dcpl).close()


def frame_grid_xml(name: str, topology_xml: str, geometry_xml: str, constant_xml: str,
                   h5name: str, series: Series, index: int, time: float) -> str:
    """The XDMF uniform grid of frame ``index`` (time ``time``, s) of a body."""
    assert series.fields is not None
    parts = [f'<Grid Name={quoteattr(name)} GridType="Uniform">'
             f'<Time Value="{float(time)!r}"/>', topology_xml, geometry_xml, constant_xml]
    for k, (centre, shape) in series.fields.items():
        full = (series.sizes[centre],) + shape
        parts.append(attribute(k, shape, centre,
                               data_item(h5name, view_path(series.path, k, index), full)))
    parts.append("</Grid>")
    return "\n      " + "\n      ".join(parts)


class XdmfGrid:
    """A body shown as one XDMF grid per frame: fixed topology and geometry, per-frame fields.

    Parameters
    ----------
    name
        Grid name, e.g. ``"ice/sheet"``.
    topology_xml, geometry_xml
        From :func:`polyvertex_topology` or :func:`cell_topology`, and :func:`geometry`.
    constant_xml
        Attributes shown in every frame (e.g. the particle volumes), or ``""``.
    series
        The body's per-frame fields.
    """

    def __init__(self, name: str, topology_xml: str, geometry_xml: str, constant_xml: str,
                 series: Series) -> None:
        self.name = name
        self.topology_xml = topology_xml
        self.geometry_xml = geometry_xml
        self.constant_xml = constant_xml
        self.series = series

    def frame_xml(self, h5name: str, index: int, time: float) -> str:
        """The XDMF grid of frame ``index`` at ``time`` (s)."""
        return frame_grid_xml(self.name, self.topology_xml, self.geometry_xml,
                              self.constant_xml, h5name, self.series, index, time)

    def head(self) -> str:
        """The opening tag of the body's temporal collection."""
        return (f'    <Grid Name={quoteattr(self.name)} GridType="Collection" '
                'CollectionType="Temporal">')


def ice_grid(h5name: str, name: str, body: str, n: int, volume: bool,
             series: Series | None) -> XdmfGrid:
    """The grid of an ice body at HDF5 path ``body``: ``n`` particles at ``x0``, and its
    ``volume`` shown in every frame if it has one."""
    constant = "" if not volume else attribute(
        "volume", (), "Node", data_item(h5name, f"{body}/volume", (n,)))
    return XdmfGrid(name, polyvertex_topology(h5name, body, n),
                    geometry(h5name, f"{body}/x0", n), constant, series)


def structure_grid(h5name: str, name: str, body: str, cell_type: str, nn: int, ne: int,
                   series: Series) -> XdmfGrid:
    """The grid of a structure at HDF5 path ``body``: ``ne`` elements over ``nn`` nodes."""
    return XdmfGrid(name, cell_topology(h5name, f"{body}/cells", cell_type, ne),
                    geometry(h5name, f"{body}/points", nn), "", series)


RANK_ICE_FIELDS = {"u": (3,), "v": (3,), "damage": ()}
"""Fields of an ice body in the per-rank files of an MPI run (m, m/s, -) and their shapes."""


class RankIceGrid:
    """An ice body written in per-rank files (``run.output_per_rank``), shown in the main
    XDMF file as one spatial collection per frame of the ranks' uniform grids, each referencing
    its own file's reference positions, vertices and per-frame views: ParaView opens the whole
    run from the one file.

    Parameters
    ----------
    name
        Grid name, e.g. ``"ice/sheet"``.
    body
        HDF5 path of the body in the per-rank files, ``/ice/<name>``.
    files
        ``(file name relative to the XDMF file, particles in it)`` of every rank, in order.
    volume
        Whether the files hold the particle volumes (shown in every frame).
    """

    def __init__(self, name: str, body: str, files: list[tuple[str, int]], volume: bool) -> None:
        self.name, self.body, self.files, self.volume = name, body, files, volume

    def head(self) -> str:
        """The opening tag of the body's temporal collection."""
        return (f'    <Grid Name={quoteattr(self.name)} GridType="Collection" '
                'CollectionType="Temporal">')

    def frame_xml(self, h5name: str, index: int, time: float) -> str:
        """The spatial collection of frame ``index`` at ``time`` (s); ``h5name`` is unused (each
        rank's grid names its own file)."""
        parts = [f'<Grid Name={quoteattr(self.name)} GridType="Collection" '
                 f'CollectionType="Spatial"><Time Value="{float(time)!r}"/>']
        for r, (h5, n) in enumerate(self.files):
            grid = ice_grid(h5, f"{self.name}.rank{r}", self.body, n, self.volume, None)
            parts += [f'<Grid Name={quoteattr(grid.name)} GridType="Uniform">',
                      grid.topology_xml, grid.geometry_xml, grid.constant_xml]
            for k, shape in RANK_ICE_FIELDS.items():
                parts.append(attribute(k, shape, "Node", data_item(
                    h5, view_path(self.body, k, index), (n,) + shape)))
            parts.append("</Grid>")
        parts.append("</Grid>")
        return "\n      " + "\n      ".join(parts)


HEAD = '<?xml version="1.0" encoding="utf-8"?>\n<Xdmf Version="3.0">\n  <Domain>\n'
TAIL = "  </Domain>\n</Xdmf>\n"
CLOSE = "\n    </Grid>\n"
MIN_RESERVE = 4096
"""Bytes of spaces kept after each temporal collection at least (see the module docstring)."""

MAX_PLANNED_RESERVE = 64 * 1024 * 1024
"""Most bytes reserved per collection for the frames a run expects (``expected_frames``)."""


class XdmfFile:
    """The XDMF file of a results file, appended to frame by frame at constant cost.

    Parameters
    ----------
    path
        The ``.xdmf`` file (written when the first frame is added).
    h5name
        The HDF5 file's name, relative to ``path``.
    expected_frames
        Frames the run expects to write (0: unknown). The first write reserves room for them
        (up to ``MAX_PLANNED_RESERVE`` bytes per collection), so that a run that writes no
        more frames than it expected never rewrites the file after its first frame.

    Notes
    -----
    Only the frame times are kept in memory; a rewrite makes every frame's text again.
    """

    def __init__(self, path: Path, h5name: str, expected_frames: int = 0) -> None:
        self.path = Path(path)
        self.h5name = h5name
        self.expected_frames = int(expected_frames)
        self.grids: list[XdmfGrid] = []
        self.times: list[float] = []
        self.rewrites = 0
        self._free: list[int] = []   # bytes of reserve left after each collection
        self._at: list[int] = []     # file offset where each collection's next frame goes

    def add_frame(self, time: float) -> None:
        """Add the next frame (time ``time``, s) of every grid to the file."""
        index = len(self.times)
        self.times.append(float(time))
        texts = [g.frame_xml(self.h5name, index, time).encode() for g in self.grids]
        if not self._at or any(len(t) > free for t, free in zip(texts, self._free)):
            self.rewrite()
            return
        fd = os.open(self.path, os.O_WRONLY)
        try:
            for k, text in enumerate(texts):
                os.pwrite(fd, text, self._at[k])
                self._at[k] += len(text)
                self._free[k] -= len(text)
        finally:
            os.close(fd)

    def set_times(self, times: Iterable[float]) -> None:
        """Replace the frames by those at ``times`` (s) (a restart) and write the file again."""
        self.times = [float(t) for t in times]
        self.rewrite()

    def rewrite(self) -> None:
        """Write the whole file, atomically, each reserve as large as its collection's text."""
        out = [HEAD.encode()]
        at, free = [], []
        pos = len(out[0])
        for g in (self.grids if self.times else []):
            head = g.head().encode()
            body = "".join(g.frame_xml(self.h5name, i, t)
                           for i, t in enumerate(self.times)).encode()
            # room for the frames still expected, each as long as the last one plus the
            # longest difference a time value (repr) makes
            planned = ((len(g.frame_xml(self.h5name, 0, self.times[-1])) + 32)
                       * (self.expected_frames - len(self.times)))
            reserve = max(MIN_RESERVE, len(head) + len(body),
                          min(planned, MAX_PLANNED_RESERVE))
            out += [head, body, b" " * reserve, CLOSE.encode()]
            at.append(pos + len(head) + len(body))
            free.append(reserve)
            pos += len(head) + len(body) + reserve + len(CLOSE)
        out.append(TAIL.encode())
        tmp = self.path.with_name(self.path.name + ".tmp")
        tmp.write_bytes(b"".join(out))
        os.replace(tmp, self.path)
        self._at, self._free = at, free
        self.rewrites += 1
