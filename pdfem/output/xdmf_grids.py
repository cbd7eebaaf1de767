"""The grids of a results file's XDMF file, laid out so that every XDMF reader of ParaView shows
each body where it is, with its name and every field.

Layout (XDMF 3)::

    <Domain>
      <Grid Name="ice/sheet" GridType="Collection" CollectionType="Temporal">   one per body
        <Grid GridType="Collection" CollectionType="Spatial"><Time Value="t"/>   one per frame
          <Grid Name="ice/sheet" GridType="Uniform"> ... </Grid>                 the body's grid
        </Grid>
        ...

A body's frame holds one uniform grid (:class:`Piece`), or, for an ice body that an MPI run
wrote per rank (``run.output_per_rank``), one per rank file, named ``ice/<body>.rank<r>`` and
referencing its own file: ParaView opens the whole run from the one file. Ice bodies come
first, then the structures (a structure's contact surface ``structure/<s>.contact`` before
it). Each grid's geometry is the frame's positions ``x`` (reference + ``u``, recorded every
frame by :class:`pdfem.output.frames.FrameSeries`): every body is drawn where it is, without a
filter. Why this layout, reader by reader (ParaView 5.11, VTK's ``IO/Xdmf2`` and ``IO/Xdmf3``;
``tests/output/test_paraview.py`` opens runs with each):

* ``XDMFReader`` names a block after a top-level grid or a collection, and renames a uniform
  grid whose name another grid of the file has (``name[1]``, ``name[2]``, ...): the body's
  name is on its temporal collection, so the block ``ice/sheet`` keeps its name at every time.
* ``Xdmf3ReaderT`` names a block after a uniform grid only (a temporal collection's grid
  loses its name), and renames a uniform grid that sits below a named spatial collection: the
  frames are unnamed spatial collections, so the grid ``ice/sheet`` keeps its name (in an
  unnamed block per body).
* ``Xdmf3ReaderS`` (the reader ``paraview.simple.OpenDataFile`` picks) reads every grid of the
  file as a piece of one dataset, without names, and ParaView draws the pieces merged,
  keeping only the arrays every piece has: so every grid carries every field of the file,
  NaN where its body has no such field (:func:`pad`), and colouring by ``damage`` colours the
  ice and ``von_mises`` the structures.
* meshio's ``TimeSeriesReader`` expects each frame to be one uniform grid and does not read
  this layout; :func:`pdfem.output.read_results` reads the HDF5 file.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING
from xml.sax.saxutils import quoteattr

import h5py

from pdfem.output.layout import POSITIONS
from pdfem.output.xdmf import (Series, attribute, cell_topology, data_item, geometry,
                               missing_values, polyvertex_topology, view_path)

if TYPE_CHECKING:
    from pdfem.output.frames import FrameSeries


@dataclass
class FieldSet:
    """The per-frame fields of a body that another process writes (a :class:`Series`)."""

    path: str
    """HDF5 path of the body in its file, e.g. ``/ice/sheet``."""
    fields: dict
    """Field name -> (centre, shape of one item)."""


class Piece:
    """One uniform grid of a body: its particles or elements in one HDF5 file.

    Parameters
    ----------
    name
        Grid name, e.g. ``"ice/sheet"`` or ``"ice/sheet.rank1"``.
    h5name
        The HDF5 file, relative to the XDMF file.
    topology_xml
        From :func:`pdfem.output.xdmf.polyvertex_topology` or
        :func:`pdfem.output.xdmf.cell_topology`.
    counts
        ``{"Node": points, "Cell": cells}`` of the grid (a particle is one Polyvertex cell).
    constants
        Fields shown in every frame: name -> (centre, item shape, HDF5 dataset).
    series
        The per-frame fields (their views ``/xdmf<path>/<field>/<frame>``), ``x`` among them.
    """

    def __init__(self, name: str, h5name: str, topology_xml: str, counts: dict[str, int],
                 constants: dict[str, tuple[str, tuple[int, ...], str]], series: Series) -> None:
        self.name, self.h5name, self.topology_xml = name, h5name, topology_xml
        self.counts, self.constants, self.series = counts, constants, series
        self.padding = ""
        """Attributes of the fields of other bodies, NaN here (:func:`pad`)."""

    def attributes(self) -> dict[str, tuple[str, tuple[int, ...]]]:
        """Every attribute the grid shows: name -> (centre, item shape)."""
        out = {k: (c, s) for k, (c, s, _) in self.constants.items()}
        out.update((k, (c, tuple(s))) for k, (c, s) in (self.series.fields or {}).items()
                   if k != POSITIONS)
        return out

    def xml(self, index: int) -> str:
        """The uniform grid of frame ``index``."""
        h5, path, counts = self.h5name, self.series.path, self.counts
        parts = [f'<Grid Name={quoteattr(self.name)} GridType="Uniform">', self.topology_xml,
                 geometry(h5, view_path(path, POSITIONS, index), counts["Node"])]
        parts += [attribute(k, s, c, data_item(h5, d, (counts[c],) + s))
                  for k, (c, s, d) in self.constants.items()]
        parts += [attribute(k, s, c, data_item(h5, view_path(path, k, index), (counts[c],) + s))
                  for k, (c, s) in self.attributes().items() if k not in self.constants]
        return "\n          ".join(parts) + self.padding + "\n        </Grid>"


class BodyGrid:
    """A body in the XDMF file: a temporal collection of one spatial collection per frame
    holding the body's pieces (see the module docstring).

    Parameters
    ----------
    name
        The body's name in the file, e.g. ``"ice/sheet"`` or ``"structure/panel"``.
    pieces
        Its uniform grids, one per file that holds part of it.
    series
        The frame series the results writer appends the body's fields to, or ``None`` (a
        body written per rank, by other processes).
    """

    def __init__(self, name: str, pieces: list[Piece], series: FrameSeries | None = None
                 ) -> None:
        self.name, self.pieces, self.series = name, pieces, series

    def head(self) -> str:
        """The opening tag of the body's temporal collection."""
        return (f'    <Grid Name={quoteattr(self.name)} GridType="Collection" '
                'CollectionType="Temporal">')

    def frame_xml(self, index: int, time: float) -> str:
        """The spatial collection of frame ``index`` at ``time`` (s)."""
        grids = "\n        ".join(p.xml(index) for p in self.pieces)
        return ('\n      <Grid GridType="Collection" CollectionType="Spatial">'
                f'<Time Value="{float(time)!r}"/>\n        {grids}\n      </Grid>')


def _ice_piece(name: str, h5name: str, body: str, n: int, volume: bool,
               series: Series) -> Piece:
    constants = {"volume": ("Node", (), f"{body}/volume")} if volume else {}
    return Piece(name, h5name, polyvertex_topology(h5name, body, n), {"Node": n, "Cell": n},
                 constants, series)


def ice_grid(h5name: str, name: str, body: str, n: int, volume: bool,
             series: FrameSeries) -> BodyGrid:
    """The grid of an ice body at HDF5 path ``body`` of file ``h5name``: ``n`` particles, and
    their ``volume`` in every frame if the file holds them."""
    return BodyGrid(name, [_ice_piece(name, h5name, body, n, volume, series)], series)


def structure_grid(h5name: str, name: str, body: str, cell_type: str, nn: int, ne: int,
                   series: FrameSeries) -> BodyGrid:
    """The grid of a structure at HDF5 path ``body``: ``ne`` elements over ``nn`` nodes."""
    piece = Piece(name, h5name, cell_topology(h5name, f"{body}/cells", cell_type, ne),
                  {"Node": nn, "Cell": ne}, {}, series)
    return BodyGrid(name, [piece], series)


RANK_ICE_FIELDS = {"u": (3,), "v": (3,), "damage": (), POSITIONS: (3,)}
"""Fields of an ice body in the per-rank files of an MPI run (m, m/s, -, m) and their shapes."""


def rank_ice_grid(name: str, body: str, files: list[tuple[str, int]], volume: bool) -> BodyGrid:
    """An ice body written in per-rank files (``run.output_per_rank``): one piece per file.

    Parameters
    ----------
    name
        The body's name, e.g. ``"ice/sheet"``.
    body
        HDF5 path of the body in the per-rank files, ``/ice/<name>``.
    files
        ``(file name relative to the XDMF file, particles in it)`` of every rank, in order.
    volume
        Whether the files hold the particle volumes.
    """
    fields = {k: ("Node", s) for k, s in RANK_ICE_FIELDS.items()}
    return BodyGrid(name, [_ice_piece(f"{name}.rank{r}", h5, body, n, volume,
                                      FieldSet(body, fields))
                           for r, (h5, n) in enumerate(files)])


def pad(grids: list[BodyGrid], file: h5py.File, h5name: str) -> None:
    """Give every piece of ``grids`` every field any of them shows, as NaN where it has none.

    ParaView's default XDMF reader (``Xdmf3ReaderS``) draws a file's grids merged and keeps only
    the arrays all of them have (module docstring). A field keeps the centre and item shape of
    the first grid that has it; the NaN it shows elsewhere is a dataset of ``file`` (the results
    file, named ``h5name`` in the XDMF file) that stores nothing
    (:func:`pdfem.output.xdmf.missing_values`).
    """
    union: dict[str, tuple[str, tuple[int, ...]]] = {}
    for grid in grids:
        for piece in grid.pieces:
            for k, v in piece.attributes().items():
                union.setdefault(k, v)
    for grid in grids:
        for piece in grid.pieces:
            own = piece.attributes()
            n = piece.counts
            piece.padding = "".join(
                "\n          " + attribute(k, s, c, data_item(h5name, missing_values(file, n[c], s),
                                                            (n[c],) + s))
                for k, (c, s) in union.items() if k not in own)
