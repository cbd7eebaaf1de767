"""What ParaView shows of an XDMF file, reader by reader, as JSON (for tests/output/test_paraview.py).

Run by ParaView's own Python, headless (no window, no render)::

    pvbatch paraview_summary.py FILE.xdmf

For each of ParaView's XDMF readers (``XDMFReader``, ``Xdmf3ReaderS``, ``Xdmf3ReaderT``) it
prints the time steps and, at the first and the last, every leaf dataset of the reader's output:
its path of block names from the root (``null`` for an unnamed block or a piece), points,
cells, bounds and, per point and cell array, the number of finite tuples; at the last time
step, the same of what a view draws: the output of ``vtkPVGeometryFilter``, the geometry
filter of ParaView's surface representation (it merges the pieces of a multi-piece dataset and
keeps the arrays every piece has). One line ``SUMMARY <json>`` on stdout.
"""

import json
import sys

import numpy as np
from paraview import servermanager
from paraview.modules.vtkPVVTKExtensionsFiltersRendering import vtkPVGeometryFilter
from paraview.simple import Delete, XDMFReader, Xdmf3ReaderS, Xdmf3ReaderT
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkCompositeDataSet

READERS = {"XDMFReader": lambda path: XDMFReader(FileNames=[path]),
           "Xdmf3ReaderS": lambda path: Xdmf3ReaderS(FileName=[path]),
           "Xdmf3ReaderT": lambda path: Xdmf3ReaderT(FileName=[path])}


def _name(data, i):
    meta = data.GetMetaData(i) if data.HasMetaData(i) else None
    if meta is None or not meta.Has(vtkCompositeDataSet.NAME()):
        return None
    return meta.Get(vtkCompositeDataSet.NAME())


def leaves(data, path=()):
    """``(path of block names, dataset)`` of every leaf of ``data``."""
    if data is None:
        return []
    if data.IsA("vtkMultiBlockDataSet"):
        return [leaf for i in range(data.GetNumberOfBlocks())
                for leaf in leaves(data.GetBlock(i), path + (_name(data, i),))]
    if data.IsA("vtkMultiPieceDataSet"):
        return [leaf for i in range(data.GetNumberOfPieces())
                for leaf in leaves(data.GetPiece(i), path + (None,))]
    return [(path, data)]


def finite(arrays):
    """Array name -> tuples whose components are all finite."""
    out = {}
    for i in range(arrays.GetNumberOfArrays()):
        a = vtk_to_numpy(arrays.GetArray(i)).astype(float)
        out[arrays.GetArrayName(i)] = int(np.isfinite(a.reshape(len(a), -1)).all(axis=1).sum())
    return out


def describe(data):
    """The leaves of ``data``: path, points, cells, bounds and finite tuples per array."""
    return [{"path": list(path), "points": ds.GetNumberOfPoints(), "cells": ds.GetNumberOfCells(),
             "bounds": list(ds.GetBounds()) if ds.GetNumberOfPoints() else None,
             "point": finite(ds.GetPointData()), "cell": finite(ds.GetCellData())}
            for path, ds in leaves(data)]


def drawn(data):
    """What a surface representation draws of ``data``."""
    geometry = vtkPVGeometryFilter()
    geometry.SetUseOutline(0)
    geometry.SetInputData(data)
    geometry.Update()
    return describe(geometry.GetOutputDataObject(0))


def summary(path):
    """Every reader's view of the XDMF file ``path``."""
    out = {}
    for name, make in READERS.items():
        reader = make(path)
        reader.UpdatePipelineInformation()
        times = [float(t) for t in np.atleast_1d(reader.TimestepValues)]
        seen = {"times": times}
        for key, t in (("first", times[0]), ("last", times[-1])):
            reader.UpdatePipeline(t)
            data = servermanager.Fetch(reader)
            seen[key] = describe(data)
            if key == "last":
                seen["drawn"] = drawn(data)
        out[name] = seen
        Delete(reader)
    return out


if __name__ == "__main__":
    print("SUMMARY " + json.dumps(summary(sys.argv[1])))
