"""The mode-shape files of ``pdfem modes``: ``modes.h5`` and ``modes.xdmf`` for ParaView.

``modes.h5`` holds, per elastic structure NAME, under ``/structures/NAME``:

- ``frequencies_hz`` (K,): the natural frequencies (Hz), ascending;
- ``shapes`` (K, Nn, 3): the mass-normalised nodal mode shapes (m kg^-1/2);
- ``points`` (Nn, 3) (m) and ``cells`` (Ne, k) int32: the structure's output mesh
  (``Structure.output_mesh()``), with attribute ``cell_type`` (meshio name).

``modes.xdmf`` has one temporal collection per structure with one frame per mode (the frame's
time is the mode number 1 .. K, so ParaView steps through the modes as an animation); the
frame shows the shape as the nodal vector field ``mode_shape`` (use Warp By Vector) and the
frequency as the constant nodal field ``frequency_hz``. Each frame references an HDF5 virtual
dataset of one row of ``shapes`` (:func:`pdfem.output.xdmf.create_view`), which meshio's
``TimeSeriesReader`` and ParaView both read. SI units.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import h5py
import numpy as np

from pdfem.output.xdmf import attribute, cell_topology, create_view, data_item, geometry, view_path


@dataclass
class StructureModes:
    """The modes of one structure and the mesh they live on.

    Attributes
    ----------
    name
        Structure name.
    frequencies_hz
        (K,) natural frequencies (Hz).
    shapes
        (K, Nn, 3) nodal mode shapes.
    points, cells, cell_type
        The output mesh: (Nn, 3) nodes (m), (Ne, k) connectivity, meshio cell type.
    """

    name: str
    frequencies_hz: np.ndarray
    shapes: np.ndarray
    points: np.ndarray
    cells: np.ndarray
    cell_type: str


def _frames_xml(h5name: str, m: StructureModes) -> str:
    """The temporal collection of one structure's modes."""
    body = f"/structures/{m.name}"
    nn, ne = len(m.points), len(m.cells)
    topology = cell_topology(h5name, f"{body}/cells", m.cell_type, ne)
    geo = geometry(h5name, f"{body}/points", nn)
    grids = []
    for i, f in enumerate(m.frequencies_hz):
        shape = attribute("mode_shape", (3,), "Node",
                          data_item(h5name, view_path(body, "shapes", i), (nn, 3)))
        freq = attribute("frequency_hz", (), "Node",
                         data_item(h5name, view_path(body, "frequency", i), (nn,)))
        grids.append(f'<Grid Name={quoteattr(f"{m.name} mode {i + 1}: {f:.6g} Hz")} '
                     f'GridType="Uniform"><Time Value="{i + 1}"/>'
                     f"{topology}{geo}{shape}{freq}</Grid>")
    head = (f'    <Grid Name={quoteattr(m.name)} GridType="Collection" '
            'CollectionType="Temporal">')
    return head + "".join("\n      " + g for g in grids) + "\n    </Grid>\n"


def write_modes(directory: str | os.PathLike, modes: list[StructureModes]) -> tuple[Path, Path]:
    """Write ``modes.h5`` and ``modes.xdmf`` into ``directory`` (created if missing).

    Parameters
    ----------
    directory
        Output directory.
    modes
        One entry per structure.

    Returns
    -------
    h5_path, xdmf_path
        The two files written (both replaced whole).
    """
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    h5_path, xdmf_path = out / "modes.h5", out / "modes.xdmf"
    with h5py.File(h5_path, "w") as f:
        for m in modes:
            g = f.create_group(f"/structures/{m.name}")
            g.create_dataset("frequencies_hz", data=np.asarray(m.frequencies_hz, np.float64))
            shapes = g.create_dataset("shapes", data=np.asarray(m.shapes, np.float64))
            g.create_dataset("points", data=np.asarray(m.points, np.float64))
            g.create_dataset("cells", data=np.asarray(m.cells, np.int32))
            g["cells"].attrs["cell_type"] = m.cell_type
            nn = len(m.points)
            freq = g.create_dataset("frequency_nodal", data=np.repeat(
                np.asarray(m.frequencies_hz, np.float64)[:, None], nn, axis=1))
            views = f.require_group(f"/xdmf/structures/{m.name}/shapes")
            fviews = f.require_group(f"/xdmf/structures/{m.name}/frequency")
            for i in range(len(m.frequencies_hz)):
                create_view(views, shapes, i, (nn, 3))
                create_view(fviews, freq, i, (nn,))
    text = ('<?xml version="1.0" encoding="utf-8"?>\n<Xdmf Version="3.0">\n  <Domain>\n'
            + "".join(_frames_xml(h5_path.name, m) for m in modes)
            + "  </Domain>\n</Xdmf>\n")
    tmp = xdmf_path.with_name(xdmf_path.name + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    os.replace(tmp, xdmf_path)
    return h5_path, xdmf_path
