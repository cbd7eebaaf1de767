"""The results of a run: writers, the output sources of its components, frames and histories.

Rank 0 writes ``results.h5``; the other MPI ranks get a :class:`NoOutput`, a writer that writes
nothing by design, so every rank runs the same calls (gathers and energy sums are collective).
With ``run.output_per_rank`` each rank also writes its own ice particles to
``results.rank<R>.h5``. The sources (:mod:`pdfem.output.source`) of a run are its ice bodies,
structures, structure loads, reactions of the ice's fixed and prescribed regions, contact pairs
and monitors; :class:`Outputs` hands their data to
the writers at every output frame and coupling step, and adds the energy balance.
"""

from __future__ import annotations

from pathlib import Path

from pdfem.coupling.facet_loads import FacetLoadSource
from pdfem.errors import InputError
from pdfem.output import ResultsWriter, rank_file
from pdfem.output.ranks import per_rank_output, rank_grid_files
from pdfem.output.source import Rows, Source


class NoOutput:
    """The results writer of MPI ranks other than 0: it takes every call of
    :class:`~pdfem.output.writer.ResultsWriter` that a run makes and writes nothing."""

    n_frames = 0

    def __init__(self, path: Path) -> None:
        self.path = path

    def add_ice_body(self, name, x0, volume=None, *, index=None) -> None:
        """Nothing."""

    def add_rank_ice_body(self, name, files, volume) -> None:
        """Nothing."""

    def add_structure(self, name, points, cells, cell_type) -> None:
        """Nothing."""

    def write_frame(self, time, ice, structures=None) -> None:
        """Nothing."""

    def append_history(self, group, time, values) -> None:
        """Nothing."""

    def resume(self, frames, history_rows) -> None:
        """Nothing."""

    def history_rows(self) -> dict[str, int]:
        """No rows."""
        return {}

    def flush(self) -> None:
        """Nothing."""

    def close(self) -> None:
        """Nothing."""


def open_results(path: Path, case_text: str, meta: dict, append: bool,
                 expected_frames: int = 0) -> ResultsWriter:
    """A new results file, or (``append``, a restart) the existing one reopened; room is
    reserved in the XDMF file for ``expected_frames`` frames."""
    if not append:
        return ResultsWriter(path, case_text, meta, expected_frames=expected_frames)
    try:
        return ResultsWriter(path, case_text, append=True, expected_frames=expected_frames)
    except (OSError, ValueError) as exc:
        raise InputError(str(path), "--restart", f"cannot continue this results file ({exc}); "
                         "give the output directory of the run that wrote the checkpoint with "
                         "--out (a run with run.output_per_rank restarts on as many ranks)"
                         ) from None


# -- the sources of a run ------------------------------------------------------------------------
class IceSource(Source):
    """An ice body: ``u``, ``v``, ``damage`` per particle every frame (gathered to rank 0, or
    this rank's particles with ``per_rank``)."""

    mesh_kind = "ice"

    def __init__(self, body, per_rank: bool) -> None:
        self.body, self.name, self.per_rank = body, body.name, per_rank

    @classmethod
    def of_run(cls, setup, per_rank: bool) -> list[Source]:
        return [cls(b, per_rank) for b in setup.bodies]

    def frame_fields(self):
        return self.body.owned_frame_fields() if self.per_rank else self.body.frame_fields()


class StructureSource(Source):
    """A structure: its fields every frame and its history row (``structures/<name>``)."""

    mesh_kind = "structure"

    def __init__(self, structure) -> None:
        self.structure, self.name = structure, structure.name

    @classmethod
    def of_run(cls, setup, per_rank: bool) -> list[Source]:
        return [cls(s) for s in setup.structures]

    def output_mesh(self):
        return self.structure.output_mesh()

    def frame_fields(self):
        return self.structure.output_fields()

    def frame_rows(self) -> Rows:
        row = self.structure.frame_history()
        return {f"structures/{self.name}": row} if row else {}


class LoadSource(Source):
    """The loads on a structure every coupling step (``loads/<name>``): the ice load (``force``
    N, ``moment`` N m about the origin, particle ``contacts``), summed over its contact pairs,
    and the resultant of its applied loads (``applied``, N); for a structure that moves freely
    (a ship) its motion (``motions/<name>``, :meth:`~pdfem.fem.base.Structure.motion_history`)."""

    def __init__(self, structure, coupler) -> None:
        self.structure, self.coupler, self.name = structure, coupler, structure.name

    @classmethod
    def of_run(cls, setup, per_rank: bool) -> list[Source]:
        return [cls(s, setup.coupler) for s in setup.structures]

    def step_rows(self) -> Rows:
        force, moment, n = self.coupler.structure_load(self.structure)
        motion = self.structure.motion_history()  # a free ship's 6 DOF (motions/<name>)
        return {f"loads/{self.name}": {"force": force, "moment": moment, "contacts": n,
                                       "applied": self.structure.applied_load()},
                **({f"motions/{self.name}": motion} if motion else {})}


class RegionSource(Source):
    """The reactions of an ice body's fixed and prescribed regions every coupling step
    (``loads/<body>.<region>``: ``force`` N in global axes, the force the support or driver
    exerts on the ice, summed over the owned particles of all ranks; collective)."""

    def __init__(self, body) -> None:
        self.body, self.name = body, body.name

    @classmethod
    def of_run(cls, setup, per_rank: bool) -> list[Source]:
        return [cls(b) for b in setup.bodies]

    def step_rows(self) -> Rows:
        return {f"loads/{self.name}.{region}": {"force": force}
                for region, force in self.body.reactions().items()}


class PairSource(Source):
    """A contact pair's load every coupling step (``contacts/<name>``)."""

    def __init__(self, pair) -> None:
        self.pair, self.name = pair, pair.name

    @classmethod
    def of_run(cls, setup, per_rank: bool) -> list[Source]:
        return [cls(p) for p in setup.pairs]

    def step_rows(self) -> Rows:
        p = self.pair
        return {f"contacts/{p.name}": {"force": p.force, "moment": p.moment,
                                       "contacts": p.contacts}}


class MonitorSource(Source):
    """A monitor probe every coupling step (``monitors/<name>``: ``u`` m, ``von_mises`` Pa,
    ``stress`` Pa: xx, yy, zz, yz, xz, xy of the element, signed, for fatigue counting)."""

    def __init__(self, name: str, structure, probe) -> None:
        self.name, self.structure, self.probe = name, structure, probe

    @classmethod
    def of_run(cls, setup, per_rank: bool) -> list[Source]:
        return [cls(name, st, probe) for name, st, probe in setup.probes]

    def step_rows(self) -> Rows:
        u, vm, stress = self.structure.probe_values(self.probe)
        return {f"monitors/{self.name}": {"u": u, "von_mises": vm, "stress": stress}}


class ShaftSource(Source):
    """A rotating structure's shaft and blade loads every coupling step (``shaft/<name>`` and
    ``shaft/<name>.<blade>``, :mod:`pdfem.motion.shaft_loads`)."""

    def __init__(self, structure) -> None:
        self.shaft, self.name = structure.shaft, structure.name

    @classmethod
    def of_run(cls, setup, per_rank: bool) -> list[Source]:
        return [cls(s) for s in setup.structures if s.shaft is not None]

    def step_rows(self) -> Rows:
        return {f"shaft/{self.name}" + (f".{k}" if k else ""): row
                for k, row in self.shaft.rows().items()}


SOURCE_KINDS = (IceSource, FacetLoadSource, StructureSource, LoadSource, RegionSource, PairSource,
                MonitorSource, ShaftSource)
"""The kinds of output source of a run, in writing order; each makes its sources of a built run
with ``of_run(setup, per_rank)``. A new kind: its class (a new file, or here) and one entry."""


def sources(setup, per_rank: bool) -> list[Source]:
    """The output sources of a built run (:class:`pdfem.run.build.Setup`), in writing order."""
    return [src for kind in SOURCE_KINDS for src in kind.of_run(setup, per_rank)]


class Outputs:
    """The writers of a run and its sources.

    Parameters
    ----------
    writer
        ``results.h5`` on rank 0, a :class:`NoOutput` elsewhere.
    ice_writer
        Where ice fields go: ``writer``, or this rank's own file with ``run.output_per_rank``.
    sources
        The run's output sources (:func:`sources`).
    energy
        The run's :class:`pdfem.run.energy.EnergyBalance`.
    """

    def __init__(self, writer, ice_writer, sources: list, energy) -> None:
        self.writer, self.ice_writer = writer, ice_writer
        self.sources, self.energy = sources, energy
        self.per_rank = ice_writer is not writer

    def register(self, setup) -> None:
        """Register the meshes of the ice bodies and the structures with the writers.

        Raises
        ------
        InputError
            When a results file being continued (restart) holds other particles.
        """
        try:
            for b in setup.bodies:
                if self.per_rank:
                    index, x0, vol = b.owned_reference()
                    self.ice_writer.add_ice_body(b.name, x0, vol, index=index)
                    counts = rank_grid_files(self.writer.path, b.layout.comm.allgather(len(index)))
                    self.writer.add_rank_ice_body(b.name, counts, vol is not None)
                else:  # gathered to rank 0 for the writer, not kept
                    self.ice_writer.add_ice_body(b.name, b.gather(b.x0), b.gather(b.vol))
        except ValueError as exc:  # only when appending: the file holds other particles
            raise InputError(str(self.ice_writer.path), "--restart", f"the results file does "
                             f"not fit this run ({exc}); a run with run.output_per_rank "
                             "restarts on as many ranks as wrote it") from None
        for src in self.sources:  # contact surfaces, then structures (the last shown by meshio)
            if src.mesh_kind == "structure":
                self.writer.add_structure(src.name, *src.output_mesh())

    def frame(self, t: float) -> dict[str, float]:
        """Write an output frame at ``t`` (s) with its history rows; returns the energy row
        (:meth:`pdfem.run.energy.EnergyBalance.row`). Collective under MPI."""
        fields = {"ice": {}, "structure": {}}
        for s in self.sources:
            if s.mesh_kind:
                fields[s.mesh_kind][s.name] = s.frame_fields()
        if self.per_rank:
            self.ice_writer.write_frame(t, fields["ice"])
            fields["ice"] = {}
        self.writer.write_frame(t, fields["ice"], structures=fields["structure"])
        for s in self.sources:
            self._append(t, s.frame_rows())
        e = self.energy.row()
        self.writer.append_history("energy", t, e)
        return e

    def step(self, t: float) -> None:
        """Write the history rows of a coupling step ending at ``t`` (s)."""
        for s in self.sources:
            self._append(t, s.step_rows())

    def _append(self, t: float, rows: Rows) -> None:
        for group, row in rows.items():
            self.writer.append_history(group, t, row)

    def resume(self, path: Path, frames: int, history_rows: dict) -> None:
        """Continue the results files after a checkpoint's frames and history rows."""
        try:
            self.writer.resume(frames, history_rows)
            if self.per_rank:
                self.ice_writer.resume(frames, {})
        except ValueError as exc:
            raise InputError(str(path), "--restart", f"the results file does not hold the "
                             f"data up to the checkpoint ({exc})") from None

    def flush(self) -> None:
        """Write what is buffered."""
        self.writer.flush()
        self.ice_writer.flush()

    def close(self) -> None:
        """Close the files (twice is allowed)."""
        self.writer.close()
        self.ice_writer.close()


def open_outputs(case, out: Path, comm, meta: dict, append: bool, particles: int = 0) -> tuple:
    """``(writer, ice_writer)`` of a run on this rank (see :class:`Outputs`); the ice goes per
    rank with ``run.output_per_rank`` or above ``particles``
    :data:`~pdfem.output.ranks.PER_RANK_PARTICLES` in total, unless the run re-partitions."""
    path = out / "results.h5"
    # a re-partitioning run moves particles between ranks: its ice is gathered whatever its size
    moves = bool(case.run.rebalance_every or case.run.rebalance_imbalance)
    per_rank = per_rank_output(case.run.output_per_rank, comm.size, 0 if moves else particles)
    if per_rank:
        meta = dict(meta, ice_per_rank=comm.size)
    frames = int(case.run.end_time / case.run.output_interval) + 2
    writer = (open_results(path, case.text, meta, append, frames) if comm.rank == 0
              else NoOutput(path))
    ice_writer = writer
    if per_rank:
        ice_writer = open_results(rank_file(path, comm.rank), case.text,
                                  {"rank": comm.rank, "ranks": comm.size}, append, frames)
    return writer, ice_writer
