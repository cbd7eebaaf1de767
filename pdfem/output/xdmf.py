"""XDMF building blocks: XML elements over HDF5 datasets, and the per-frame views they name.

An XDMF file (XDMF 3) describes grids whose arrays live in HDF5 files: a ``DataItem`` names
``<file>:<dataset>`` with the file relative to the XDMF file, so the two can be moved
together. These helpers write the elements (data items, attributes, geometry, topologies) and
the HDF5 side: the particle vertices of a Polyvertex topology, and the per-frame views.

A view (:func:`create_view`) is an HDF5 virtual dataset that maps frame F of an (F, N, ...)
dataset (no copy): each frame's grid names whole datasets, which every XDMF reader reads
(meshio's ``TimeSeriesReader`` cannot read XDMF hyperslabs). The grids of a results file are
in :mod:`pdfem.output.xdmf_grids`, its file in :mod:`pdfem.output.xdmf_file`, the mode shapes'
in :mod:`pdfem.output.modes`.
"""

from __future__ import annotations

from typing import Protocol
from xml.sax.saxutils import escape, quoteattr

import h5py
import numpy as np


class Series(Protocol):
    """What a grid of frames reads from the frame series it shows
    (:class:`pdfem.output.frames.FrameSeries`): its HDF5 ``path`` and its ``fields`` (name ->
    (centre, shape per entity); ``None`` before the first frame)."""

    path: str
    fields: dict | None


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


def missing_values(file: h5py.File, n: int, shape: tuple[int, ...]) -> str:
    """HDF5 path of an (n,) + ``shape`` float64 dataset of NaN in ``file``, made if absent.

    The dataset is chunked and never written, so HDF5 stores no chunk of it (it reads as its
    fill value, NaN): it costs a few hundred bytes of metadata whatever ``n``. The grids show
    it as a field a body does not have (:func:`pdfem.output.xdmf_grids.pad`).
    """
    path = f"/xdmf/missing/{n}" + "".join(f"x{k}" for k in shape)
    if path not in file:
        file.create_dataset(path, shape=(n,) + shape, dtype=np.float64, chunks=True,
                            fillvalue=np.nan)
    return path
