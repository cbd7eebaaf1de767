"""Typed bond data: the named tuples of arrays that the bond kernels take.

numba compiles a ``NamedTuple`` of arrays like the arrays themselves (a tuple of array
pointers and shapes, unpacked in registers), so a kernel can take a handful of these instead
of dozens of loose arrays, at no cost in speed. The tuples hold references, never copies: a
kernel that writes ``Particles.theta`` writes the body's array.

- :class:`Bonds`: a body's unique pairs i < j grouped by i (CSR), reference lengths and signed
  float32 weights (a negative weight marks a broken bond: 16 bytes per bond);
- :class:`Particles`: the per-particle arrays a force pass reads and writes.

Units: m, m^3, m^5, N/m^3.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class Bonds(NamedTuple):
    """A body's bonds (unique pairs i < j grouped by i).

    Attributes
    ----------
    row_ptr
        (N+1,) int64: the bonds of row i are ``row_ptr[i]:row_ptr[i+1]``.
    nbr
        (P,) int32: the partner j > i of each bond.
    xi_len
        (P,) float64 reference bond lengths |xi| (m).
    weight
        (P,) float32 bond weights omega = w beta, negative where the bond is broken.
    """

    row_ptr: np.ndarray
    nbr: np.ndarray
    xi_len: np.ndarray
    weight: np.ndarray

    @property
    def n(self) -> int:
        """Number of particles (rows)."""
        return self.row_ptr.shape[0] - 1

    @property
    def n_bonds(self) -> int:
        """Number of bonds."""
        return self.nbr.shape[0]

    def broken(self) -> np.ndarray:
        """(P,) uint8 broken flags (1 where the weight is negative), a copy."""
        return (self.weight < 0).view(np.uint8)

    def row_of(self) -> np.ndarray:
        """(P,) int64 lower end i of every bond."""
        return np.repeat(np.arange(self.n, dtype=np.int64), np.diff(self.row_ptr))


class Particles(NamedTuple):
    """The per-particle arrays of a force pass (N particles).

    Attributes
    ----------
    y
        (N, 3) current positions (m).
    vol
        (N,) volumes (m^3).
    m
        (N,) weighted volumes of all initial bonds (m^5).
    theta
        (N,) dilatations (written by the dilatation pass).
    f
        (N, 3) force density (N/m^3; written by the force pass).
    nofail
        (N,) uint8, 1 = the particle's bonds never break.
    """

    y: np.ndarray
    vol: np.ndarray
    m: np.ndarray
    theta: np.ndarray
    f: np.ndarray
    nofail: np.ndarray
