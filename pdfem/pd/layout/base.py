"""The layout of an ice body over the processes: which particles are here, which are owned.

An :class:`~pdfem.pd.body.IceBody` holds *local* particles: those this process answers for (the
*owned* ones) and, under MPI, copies of their bond partners owned elsewhere (the *halo*). The
body's physics runs over its local arrays and asks its layout for everything that crosses
processes:

- ``exchange(values)``: overwrite the halo rows of a per-particle array with their owners' values
  (before the dilatation and force passes that read them);
- ``owned_sum(values)``: a per-particle quantity summed over the owned particles of every
  process, correctly rounded (:mod:`pdfem.parallel.exact_sum`), so the same on 1 and N ranks;
- ``total(values)``: the same for rows already restricted to owned particles;
- ``allsum(value)``: a per-process count or partial summed over the processes;
- ``gather(values)``: the owned rows of a per-particle array in global order on rank 0.

Two layouts implement it: :class:`WholeLayout` (one process holds the whole body: every
particle is owned, nothing to exchange) and :class:`~pdfem.pd.layout.halo.HaloLayout` (a rank's
part of a body split over MPI ranks). The physics never asks which one it has.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from pdfem.parallel.comm import SerialComm
from pdfem.parallel.exact_sum import exact_sum, exact_weighted_sums


class Layout(Protocol):
    """What an ice body needs to know and do across processes (see the module docstring)."""

    comm: object
    """The communicator (``pdfem.parallel.comm``: ``rank``, ``size``, collectives)."""
    owned: np.ndarray
    """(n,) bool: the local particles this process owns."""
    gid: np.ndarray
    """(n,) int64 ascending global numbers of the local particles."""
    n_global: int
    """Particles of the whole body."""
    version: int
    """Incremented when particles move between processes (local numbers change)."""
    counted_rows: np.ndarray
    """(n,) uint8 rows whose bonds this process counts (its owned particles), or size 0 for
    every row (a whole body)."""

    def exchange(self, values: np.ndarray) -> None:
        """Overwrite the halo rows of ``values`` (n, ...) with their owners' values."""

    def owned_sum(self, values: np.ndarray):
        """Correctly rounded sum of ``values`` ((n,) -> float, (n, k) -> (k,)) over the owned
        rows of every process (collective)."""

    def total(self, values: np.ndarray):
        """Correctly rounded sum of every row of ``values`` (rows of owned particles only)
        over every process (collective)."""

    def weighted_sums(self, w: np.ndarray, values: np.ndarray, segments: list) -> np.ndarray:
        """Per segment of rows (this process's rows, owned particles only), the correctly
        rounded ``sum w`` and ``sum w values`` over every process, ``(S, 1 + k)``
        (:func:`pdfem.parallel.exact_sum.exact_weighted_sums`; collective)."""

    def allsum(self, value):
        """A per-process value summed over the processes, in rank order (collective)."""

    def gather(self, values: np.ndarray) -> np.ndarray | None:
        """The owned rows of ``values`` in global order on rank 0, None elsewhere."""


class WholeLayout:
    """One process holds the whole body (:class:`Layout`): all owned, nothing exchanged.

    Parameters
    ----------
    n
        Number of particles.
    """

    comm = SerialComm()
    version = 0
    exchange_seconds = 0.0
    rebalances = 0
    rebalance_seconds = 0.0
    partition = "whole"

    def __init__(self, n: int) -> None:
        self.n_global = int(n)
        self.owned = np.ones(n, dtype=np.bool_)
        self.gid = np.arange(n, dtype=np.int64)
        self.counted_rows = np.zeros(0, dtype=np.uint8)

    def exchange(self, values: np.ndarray) -> None:
        """Nothing: there is no halo."""

    def owned_sum(self, values: np.ndarray):
        """The correctly rounded sum of ``values`` over every row."""
        return exact_sum(values, self.comm)

    def total(self, values: np.ndarray):
        """The correctly rounded sum of every row of ``values``."""
        return exact_sum(values, self.comm)

    def weighted_sums(self, w: np.ndarray, values: np.ndarray, segments: list) -> np.ndarray:
        """Per segment of rows, ``sum w`` and ``sum w values``, correctly rounded over the
        processes (:func:`pdfem.parallel.exact_sum.exact_weighted_sums`; collective)."""
        return exact_weighted_sums(w, values, segments, self.comm)

    def allsum(self, value):
        """``value`` itself."""
        return value

    def gather(self, values: np.ndarray) -> np.ndarray:
        """``values`` itself (already in global order)."""
        return values
