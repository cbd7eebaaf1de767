"""The energy released by the bonds that broke in a step: numba kernels over the pair list.

When bonds break, the ice's strain energy at the current positions y drops by what the broken
bonds held: the fracture dissipation of the step is W(y; B) - W(y; B') with B the bond set
before and B' the one after breaking, each with the dilatation of its own bond set (as
:func:`pdfem.pd.bonds.pair_loop.strain_energy` takes it). The LPS energy density W_i (module doc of
:mod:`pdfem.pd.bonds.pair_loop`) depends only on particle i's bonds, through theta_i and its
deviatoric sum, so only the end particles of the new broken bonds (the *hit* particles) change::

    dW = sum_{i hit} V_i (W_i(y; B) - W_i(y; B'))      (J)

Layout and flags as in :mod:`pdfem.pd.bonds.pair_loop` (``broken`` uint8 flags or ``signed``
weights). ``seen`` is a bit set, one bit per pair (bit k % 8 of byte k // 8), of the bonds
already accounted as broken; a bond broken now but not seen is new. The work is three light
passes: over the rows where the force pass broke bonds (the chunks with a non-zero count),
then twice over the rows that can hold bonds of hit particles (from the smallest ``first_row``
of a hit particle, the first row with a bond to it, up to the largest hit particle), then
the new bonds are marked seen. Serial, and run only in steps that broke bonds. SI units.
"""

from __future__ import annotations

import numba
import numpy as np

from pdfem.parallel.kernels import FASTMATH, fma
from pdfem.pd.bonds.chunk_kernels import U64
from pdfem.pd.bonds.lps_law import (
    bond_length,
    bond_vector,
    deviatoric_extension,
    dilatation_of,
    dilatation_term,
    energy_density,
    is_broken,
)

_JIT = dict(cache=True, fastmath=FASTMATH, error_model="numpy")


@numba.njit(cache=True, inline="always")
def _bit(seen, k):
    """Whether bit k of the bit set ``seen`` is set."""
    return (seen[k >> U64(3)] >> (k & U64(7))) & np.uint8(1) != 0


@numba.njit(**_JIT)
def first_rows(row_ptr, nbr):
    """(N,) int64: for each particle p the first row i <= p holding a bond (i, p), else p."""
    n = row_ptr.shape[0] - 1
    out = np.arange(n)
    for i in range(n - 1, -1, -1):  # descending: the smallest row writes last
        for k in range(row_ptr[i], row_ptr[i + 1]):
            out[nbr[k]] = i
    return out


@numba.njit(**_JIT)
def seen_bits(row_ptr, nbr, broken, signed, wt):
    """The bit set of the bonds broken now (``signed``: negative weight; else the flags)."""
    p = nbr.shape[0]
    seen = np.zeros((p + 7) // 8, dtype=np.uint8)
    for k in range(U64(p)):
        if is_broken(signed, wt[k], broken, k):
            seen[k >> U64(3)] |= np.uint8(1) << np.uint8(k & U64(7))
    return seen


@numba.njit(**_JIT)
def _mark_hits(bonds, seen, cb, counts, owned, hit):
    """Mark the ends of the new broken bonds in the rows of chunks with counts > 0; returns
    (number of new bonds, of them those in ``owned`` rows (all if size 0), smallest and
    largest hit particle)."""
    row_ptr, nbr, wt, broken = bonds.row_ptr, bonds.nbr, bonds.weight, bonds.broken
    signed = broken.shape[0] == 0
    new = 0
    counted = 0
    all_owned = owned.shape[0] == 0
    lo = hit.shape[0]
    hi = -1
    for c in range(cb.shape[0] - 1):
        if counts[c] == 0:
            continue
        for i in range(cb[c], cb[c + 1]):
            for k in range(U64(row_ptr[i]), U64(row_ptr[i + 1])):
                if is_broken(signed, wt[k], broken, k) and not _bit(seen, k):
                    j = nbr[k]
                    hit[i] = 1
                    hit[j] = 1
                    new += 1
                    if all_owned or owned[i]:
                        counted += 1
                    lo = min(lo, i)
                    hi = max(hi, j)
    return new, counted, lo, hi


@numba.njit(**_JIT)
def _mark_seen(bonds, seen, cb, counts):
    """Set the bits of every bond broken now in the rows of chunks with counts > 0."""
    row_ptr, wt, broken = bonds.row_ptr, bonds.weight, bonds.broken
    signed = broken.shape[0] == 0
    for c in range(cb.shape[0] - 1):
        if counts[c] == 0:
            continue
        for k in range(U64(row_ptr[cb[c]]), U64(row_ptr[cb[c + 1]])):
            if is_broken(signed, wt[k], broken, k):
                seen[k >> U64(3)] |= np.uint8(1) << np.uint8(k & U64(7))


@numba.njit(**_JIT)
def _hit_sums(bonds, P, seen, hit, rows, theta, dev, acc):
    """Over the bonds in rows r0..r1-1 with a hit end, before (column 0) and after (column 1)
    breaking, add into ``acc`` (N, 2): the dilatation sums sum omega l e V, or with ``dev``
    the deviatoric sums sum omega e_d^2 V with the dilatations ``theta`` (N, 2)."""
    row_ptr, nbr, xi_len, wt, broken = bonds.row_ptr, bonds.nbr, bonds.xi_len, bonds.weight, \
        bonds.broken
    signed = broken.shape[0] == 0
    y, vol = P.y.reshape(P.y.size), P.vol
    r0, r1 = rows
    for i in range(r0, r1):
        hi_ = hit[i] != 0
        yi0 = y[3 * i]
        yi1 = y[3 * i + 1]
        yi2 = y[3 * i + 2]
        for k in range(U64(row_ptr[i]), U64(row_ptr[i + 1])):
            j = U64(nbr[k])
            if not (hi_ or hit[j] != 0):
                continue
            w = wt[k]
            now = is_broken(signed, w, broken, k)
            if now and _bit(seen, k):
                continue  # broken in an earlier step: in neither set
            w = abs(w)
            l = xi_len[k]
            d0, d1, d2 = bond_vector(y, U64(3) * j, yi0, yi1, yi2)
            r = bond_length(d0, d1, d2)
            e = r - l
            for col in range(2):
                if col == 1 and now:
                    continue  # broke in this step: before only
                if hi_:
                    if dev:
                        ed = deviatoric_extension(e, theta[i, col] / 3.0, l)
                        acc[i, col] += ed * ed * w * vol[j]
                    else:
                        acc[i, col] = fma(dilatation_term(w, l, r), vol[j], acc[i, col])
                if hit[j] != 0:
                    if dev:
                        ed = deviatoric_extension(e, theta[j, col] / 3.0, l)
                        acc[j, col] += ed * ed * w * vol[i]
                    else:
                        acc[j, col] = fma(dilatation_term(w, l, r), vol[i], acc[j, col])


@numba.njit(**_JIT)
def released_energy(bonds, P, K, mu, owned, seen, first_row, cb, counts):
    """Energy (J) released by the bonds that broke since ``seen`` was last updated, over the
    hit particles that are ``owned`` (size 0: all), and the number of those bonds in ``owned``
    rows (each bond of a split body counted on one rank); marks the bonds in ``seen``."""
    m = P.m
    n = bonds.row_ptr.shape[0] - 1
    hit = np.zeros(n, dtype=np.uint8)
    new, counted, lo, hi = _mark_hits(bonds, seen, cb, counts, owned, hit)
    if new == 0:
        return 0.0, 0
    r0 = lo
    for p in range(lo, hi + 1):
        if hit[p] != 0:
            r0 = min(r0, first_row[p])
    acc = np.zeros((n, 2))
    theta = np.zeros((n, 2))
    _hit_sums(bonds, P, seen, hit, (r0, hi + 1), theta, False, acc)
    for p in range(lo, hi + 1):
        if hit[p] != 0:
            for col in range(2):
                theta[p, col] = dilatation_of(acc[p, col], m[p])
                acc[p, col] = 0.0
    _hit_sums(bonds, P, seen, hit, (r0, hi + 1), theta, True, acc)
    total = 0.0
    all_owned = owned.shape[0] == 0
    for p in range(lo, hi + 1):
        if hit[p] != 0 and (all_owned or owned[p]):
            before = energy_density(K, mu, theta[p, 0], acc[p, 0], m[p])
            after = energy_density(K, mu, theta[p, 1], acc[p, 1], m[p])
            total += (before - after) * P.vol[p]
    _mark_seen(bonds, seen, cb, counts)
    return total, counted
