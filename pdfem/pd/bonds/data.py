"""Typed bond data: the named tuples of arrays that the bond kernels take.

numba compiles a ``NamedTuple`` of arrays like the arrays themselves (a tuple of array
pointers and shapes, unpacked in registers), so a kernel can take a handful of these instead
of dozens of loose arrays, at no cost in speed. The tuples hold references, never copies: a
kernel that writes ``Particles.theta`` writes the body's array.

- :class:`Bonds`: a body's unique pairs i < j grouped by i (CSR), reference lengths and signed
  float32 weights (a negative weight marks a broken bond: 16 bytes per bond), or separate
  uint8 broken flags;
- :class:`Particles`: the per-particle arrays a force pass reads and writes;
- :class:`Blocks`: the blocks of a pair loop and their overflow buffers
  (:mod:`pdfem.pd.bonds.workspace`);
- :class:`LawArrays`: what a general failure law adds to the force pass (crushed bonds, their
  shear springs, strength factors).

numba loses writes made through a named tuple's attributes, or through a tuple unpacked into
names, inside a ``prange`` body (numba issues 5872, 7135, 10338); indexing by position works.
Kernel code inside ``prange`` bodies therefore indexes these tuples with the field positions
below (``bonds[WEIGHT]``, not ``bonds.weight``); ``tests/pd/test_pair_kernels.py``... checks
that every write arrives (the kernels' results against the full-family loop and a serial run).

Units: m, m^3, m^5, N/m^3.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

SIGNED = np.zeros(0, dtype=np.uint8)
"""As ``Bonds.broken``: "bond k is broken iff weight[k] < 0" (read-only by convention)."""


# field positions, for kernel code inside prange bodies (see the module docstring)
ROW_PTR, NBR, XI_LEN, WEIGHT, BROKEN = range(5)
Y, VOL, M, THETA, F, NOFAIL = range(6)
PTR, SPLIT, OV_PTR, OV, COUNTS = range(5)
COEF, AUX, LIM, CRUSH_YIELD, REST, OWNED, CRUSH, SLIP, Y0, SHEAR = range(10)


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
    broken
        (P,) uint8 broken flags, or :data:`SIGNED` (size 0): a bond is broken when its weight
        is negative (how ice bodies keep them).
    """

    row_ptr: np.ndarray
    nbr: np.ndarray
    xi_len: np.ndarray
    weight: np.ndarray
    broken: np.ndarray = SIGNED

    @property
    def n(self) -> int:
        """Number of particles (rows)."""
        return self.row_ptr.shape[0] - 1

    @property
    def n_bonds(self) -> int:
        """Number of bonds."""
        return self.nbr.shape[0]

    def broken_flags(self) -> np.ndarray:
        """(P,) uint8 broken flags, a copy (1 where the weight is negative, with
        :data:`SIGNED`)."""
        if self.broken.shape[0] == 0 and self.nbr.shape[0] != 0:
            return (self.weight < 0).view(np.uint8)
        return self.broken.copy()

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


class Blocks(NamedTuple):
    """The blocks of a pair loop (:class:`~pdfem.pd.bonds.workspace.PairWorkspace`).

    Attributes
    ----------
    ptr
        (C+1,) int64 first row of each block.
    split
        (C,) int64 first row of each block with a partner beyond the block.
    ov_ptr
        (C+1,) int64 offsets of each block's overflow rows in ``ov``.
    ov
        (ov_ptr[-1], 3) float64 overflow buffer.
    counts
        (C,) int64 bonds each block broke in the last force pass.
    """

    ptr: np.ndarray
    split: np.ndarray
    ov_ptr: np.ndarray
    ov: np.ndarray
    counts: np.ndarray


class LawArrays(NamedTuple):
    """The per-particle and per-bond arrays of a force pass under a general failure law.

    Attributes
    ----------
    coef, aux
        (N, 2) per-particle force coefficients (a, b) and halves of the dilatation and
        strength factor (:func:`pdfem.pd.bonds.lps_law.force_coefficients`).
    lim
        (6,) stretch-bound coefficients (t0, t1, c0, c1, d0, d1).
    crush_yield
        The crushed bonds' yield compression (stretch).
    rest
        (P,) float32 plastic rest stretch of crushed bonds (NaN: broken for good); size 0 when
        broken bonds never push.
    owned
        (N,) uint8 rows whose crushed bonds' dissipation counts (size 0: all).
    crush
        (C,) energy (J) each block's crushed bonds dissipated in the last pass.
    slip, y0, shear
        Shear springs of crushed bonds: (P, 3) float32 stretch (size 0: none), positions at the
        step's start and (mu, kappa, advance) (:mod:`pdfem.pd.failure.crushed_shear`).
    """

    coef: np.ndarray
    aux: np.ndarray
    lim: np.ndarray
    crush_yield: float
    rest: np.ndarray
    owned: np.ndarray
    crush: np.ndarray
    slip: np.ndarray
    y0: np.ndarray
    shear: np.ndarray
