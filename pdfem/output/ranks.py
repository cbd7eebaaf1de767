"""Per-rank ice files of an MPI run and their merge into one result.

An MPI run writes its ice per rank when ``run.output_per_rank`` is set or, by default, when
its ice bodies have more than :data:`PER_RANK_PARTICLES` particles in total
(:func:`per_rank_output`): gathering every frame to rank 0 would need the whole body's fields
in one process. Each rank writes the ice particles it owns to ``results.rank<R>.h5`` beside
``results.h5`` (with ``/ice/<body>/index``, the global particle numbers); ``results.h5`` holds the
structures and histories, and its ``/meta`` attribute ``ice_per_rank`` the number of ranks;
its XDMF file shows, per frame, every rank's part of an ice body, each from its own file
(:func:`pdfem.output.xdmf_grids.rank_ice_grid`), so ParaView opens the whole run from it.
:func:`pdfem.output.reader.read_results` puts the parts back together in global order.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np


PER_RANK_PARTICLES = 2_000_000
"""Total ice particles above which an MPI run writes its ice per rank by default: 2 M particles
make 48 MB per frame of ``u`` and ``v`` (float64) plus the gather's copies on rank 0."""


def per_rank_output(requested: bool, ranks: int, particles: int) -> bool:
    """Whether a run on ``ranks`` ranks with ``particles`` ice particles in total writes its
    ice per rank: ``requested`` (``run.output_per_rank``) or more than
    :data:`PER_RANK_PARTICLES` particles, and more than one rank."""
    return ranks > 1 and (bool(requested) or particles > PER_RANK_PARTICLES)


def rank_grid_files(path: str | os.PathLike, counts: list[int]) -> list[tuple[str, int]]:
    """``(per-rank file name, particles in it)`` of every rank beside a results file, for
    :meth:`pdfem.output.writer.ResultsWriter.add_rank_ice_body`."""
    return [(rank_file(path, r).name, int(n)) for r, n in enumerate(counts)]


def rank_file(path: str | os.PathLike, rank: int) -> Path:
    """The per-rank ice file of MPI rank ``rank`` beside a results file:
    ``results.h5`` -> ``results.rank<rank>.h5``."""
    p = Path(path)
    return p.with_name(f"{p.stem}.rank{rank}{p.suffix}")


def rank_files(path: str | os.PathLike, ranks: int) -> list[Path]:
    """The per-rank ice files of ranks 0 .. ``ranks - 1`` beside a results file.

    Raises
    ------
    FileNotFoundError
        If one of them is missing.
    """
    files = [rank_file(path, r) for r in range(ranks)]
    for file in files:
        if not file.is_file():
            raise FileNotFoundError(f"{file}: the per-rank ice file of this results file is "
                                    "missing (keep the results.rank*.h5 files beside it)")
    return files


def merge_rank_files(out: dict, parts: list[dict]) -> None:
    """Put the ice of the per-rank files into ``out`` in global particle order, keeping the
    frames that every file holds.

    Parameters
    ----------
    out
        ``read_results`` of the main file; its ice, time and structure frames are replaced.
    parts
        ``read_results`` of each per-rank file, in rank order.
    """
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
