"""A small XDMF reader for the tests, independent of pdfem's writer: the standard library's XML
parser and h5py, following the XDMF model (xdmf.org, "XDMF Model and Format").

:func:`read_xdmf` returns, per temporal collection of the domain, its frames: a frame is a
child of the collection, with its ``<Time>``; its uniform grids are the child itself or, for a
spatial collection, the uniform grids inside it. Every ``DataItem`` (``Format="HDF"``,
``file:dataset``, the file relative to the XDMF file) is read with h5py and checked against its
declared ``Dimensions``. ParaView's own readers are tests/output/test_paraview.py's reference.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import h5py
import numpy as np


@dataclass
class Grid:
    """A uniform grid: topology type, connectivity, positions and attributes."""

    topology: str
    cells: np.ndarray
    points: np.ndarray
    point_data: dict[str, np.ndarray] = field(default_factory=dict)
    cell_data: dict[str, np.ndarray] = field(default_factory=dict)


@dataclass
class Frame:
    """One time of a temporal collection: its uniform grids by name."""

    time: float
    grids: dict[str, Grid]


def read_item(item: ET.Element, directory: Path) -> np.ndarray:
    """The array a ``DataItem`` names, of its declared shape."""
    assert item.get("Format") == "HDF", item.attrib
    name, path = item.text.strip().split(":")
    with h5py.File(directory / name, "r") as f:
        a = f[path][()]
    assert a.shape == tuple(int(d) for d in item.get("Dimensions").split()), (path, a.shape)
    return a


def _grid(element: ET.Element, directory: Path) -> Grid:
    topology = element.find("Topology")
    grid = Grid(topology.get("TopologyType"), read_item(topology.find("DataItem"), directory),
                read_item(element.find("Geometry/DataItem"), directory))
    for a in element.findall("Attribute"):
        data = grid.point_data if a.get("Center") == "Node" else grid.cell_data
        data[a.get("Name")] = read_item(a.find("DataItem"), directory)
    return grid


def read_xdmf(path: str | Path) -> dict[str, list[Frame]]:
    """Every temporal collection of the XDMF file ``path``: name -> its frames, in order."""
    path = Path(path)
    root = ET.parse(path).getroot()
    out = {}
    for collection in root.find("Domain").findall("Grid"):
        assert collection.get("CollectionType") == "Temporal", collection.attrib
        frames = []
        for child in collection.findall("Grid"):
            uniform = [child] if child.get("GridType") == "Uniform" else child.findall("Grid")
            assert all(g.get("GridType") == "Uniform" for g in uniform)
            frames.append(Frame(float(child.find("Time").get("Value")),
                                {g.get("Name"): _grid(g, path.parent) for g in uniform}))
        out[collection.get("Name")] = frames
    return out
