"""Reference configuration of the bodies in a results file: ice particles and structure meshes.

:func:`store_ice_body` and :func:`store_structure` validate what the writer is given and store
it (``/ice/<body>/x0``, ``volume``, ``index``; ``/structure/<name>/points``, ``cells``), or,
when a run is continued in an existing file, check that it matches what the file holds.
"""

from __future__ import annotations

import h5py
import numpy as np

from pdfem.output.xdmf import XDMF_TOPOLOGY


def _points(what: str, x: np.ndarray) -> np.ndarray:
    x = np.ascontiguousarray(x, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3 or x.shape[0] == 0:
        raise ValueError(f"{what} has shape {x.shape}, expected (N, 3) with N > 0")
    return x


def store_ice_body(file: h5py.File, path: str, x0: np.ndarray, volume: np.ndarray | None,
                   index: np.ndarray | None, append: bool) -> int:
    """Validate and store (or, with ``append``, compare) an ice body's reference configuration.

    Parameters
    ----------
    file
        The results file, open for writing.
    path
        The body's group, ``/ice/<name>``.
    x0
        (N, 3) reference particle positions, m.
    volume
        (N,) particle volumes, m^3, or ``None``.
    index
        (N,) global particle numbers of a per-rank file, or ``None``.
    append
        Only check that the file's body has as many particles.

    Returns
    -------
    int
        The number of particles N.

    Raises
    ------
    ValueError
        If a shape is wrong, or the file's body differs.
    """
    name = path.rsplit("/", 1)[1]
    x0 = _points(f"x0 of ice body {name!r}", x0)
    n = x0.shape[0]
    if volume is not None:
        volume = np.ascontiguousarray(volume, dtype=np.float64)
        if volume.shape != (n,):
            raise ValueError(f"volume of ice body {name!r} has shape {volume.shape}, "
                             f"expected ({n},)")
    if append:
        if file[path]["x0"].shape != x0.shape:
            raise ValueError(f"ice body {name!r} has {n} particles, the results file "
                             f"{file[path]['x0'].shape[0]}")
        return n
    g = file.create_group(path)
    g.attrs["kind"] = "ice_body"
    g.create_dataset("x0", data=x0)
    if volume is not None:
        g.create_dataset("volume", data=volume)
    if index is not None:
        g.create_dataset("index", data=np.asarray(index, dtype=np.int64))
    return n


def store_structure(file: h5py.File, path: str, points: np.ndarray, cells: np.ndarray,
                    cell_type: str, append: bool) -> tuple[int, int]:
    """Validate and store (or, with ``append``, compare) a structure's mesh.

    Parameters
    ----------
    file
        The results file, open for writing.
    path
        The structure's group, ``/structure/<name>``.
    points
        (Nn, 3) reference node positions, m.
    cells
        (Ne, k) connectivity into ``points`` in VTK / meshio node order.
    cell_type
        ``"tetra"``, ``"hexahedron"``, ``"triangle"`` or ``"quad"``.
    append
        Only check that the file's mesh has the same shapes.

    Returns
    -------
    (int, int)
        The numbers of nodes Nn and elements Ne.

    Raises
    ------
    ValueError
        If the cell type, a shape or a node number is wrong, or the file's mesh differs.
    """
    name = path.rsplit("/", 1)[1]
    points = _points(f"points of structure {name!r}", points)
    if cell_type not in XDMF_TOPOLOGY:
        raise ValueError(f"cell_type {cell_type!r} of structure {name!r} is not one of "
                         f"{sorted(XDMF_TOPOLOGY)}")
    k = XDMF_TOPOLOGY[cell_type][1]
    cells = np.ascontiguousarray(cells, dtype=np.int32)
    if cells.ndim != 2 or cells.shape[1] != k or cells.shape[0] == 0:
        raise ValueError(f"cells of structure {name!r} have shape {cells.shape}, expected "
                         f"(Ne, {k}) with Ne > 0 for {cell_type!r}")
    nn, ne = points.shape[0], cells.shape[0]
    if cells.min() < 0 or cells.max() >= nn:
        raise ValueError(f"cells of structure {name!r} index nodes outside 0..{nn - 1}")
    if append:
        if file[path]["points"].shape != points.shape or file[path]["cells"].shape != cells.shape:
            raise ValueError(f"structure {name!r} differs from the one in the results file")
        return nn, ne
    g = file.create_group(path)
    g.attrs["kind"] = "structure"
    g.create_dataset("points", data=points)
    g.create_dataset("cells", data=cells).attrs["cell_type"] = cell_type
    return nn, ne
