"""The pair loops of an LPS time step: dilatation, then forces with bond breaking.

The two passes of :func:`pdfem.pd.bonds.pair_loop.dilatation_and_forces` (and of
:func:`~pdfem.pd.bonds.pair_loop.dilatation` and :func:`~pdfem.pd.bonds.pair_loop.forces`) over the
unique bonds i < j grouped by i (data layout: :mod:`pdfem.pd.bonds.pair_loop`), chunked for
race-free deterministic threading (:mod:`pdfem.pd.bonds.chunk_kernels`). The physics of a bond is
:mod:`pdfem.pd.bonds.lps_law`'s. The row loop exists in one copy per combination of the flags
``signed`` / ``store_r`` (``use_r``): each flag is then a constant inside its copy of the hot
loop (no per-bond tests of it, fewer live registers). Index arithmetic is unsigned (``U64``):
numba then emits no negative-index wraparound code for the gathers and scatters. The
multiply-adds into the sums are explicit :func:`~pdfem.parallel.kernels.fma` calls, not
fastmath contraction: a cache-loaded kernel then computes the same bits as a fresh compile.

The kernels take the named tuples of :mod:`pdfem.pd.bonds.data` and take their arrays out
before the ``prange``: numba loses writes made through a tuple's arrays inside a ``prange``
body (numba issues 5872, 7135, 10338; also through plain tuples unpacked there, measured), so
the row loops, inlined into the body, take the arrays one by one. Inlined there, they run in
numba's parallel-loop function, where the ice-law row loop is twice as fast as in an ordinary
compiled function (measured: 0.24 s against 0.50 s per pass on 59 M bonds).
"""

from __future__ import annotations

import numba
import numpy as np
from numba import prange

from pdfem.parallel.kernels import FASTMATH, fma, twin
from pdfem.pd.bonds.chunk_kernels import U64, add_overflow1, add_overflow3
from pdfem.pd.bonds.pair_force_kernels import apply_crushed_shear, apply_pair_force
from pdfem.pd.bonds.lps_law import (
    bond_length,
    bond_vector,
    breaks,
    breaks_stretch,
    crushed_bond,
    crushed_bond_energy,
    crushed_rest,
    dilatation_of,
    dilatation_term,
    is_broken,
    mark_broken,
    pair_force_scalar,
)


@numba.njit(cache=True, inline="always", fastmath=FASTMATH, error_model="numpy")
def _dilatation_row(i, y, row_ptr, nbr, xi_len, broken, signed, vol, wt, theta, checked, r1, ov,
                    base, rbuf, store_r):
    """Row i of the pair-loop dilatation (``checked``: partners may lie beyond row r1)."""
    yi0 = y[3 * i]
    yi1 = y[3 * i + 1]
    yi2 = y[3 * i + 2]
    vi = vol[i]
    acc = 0.0
    for k in range(U64(row_ptr[i]), U64(row_ptr[i + 1])):
        w = wt[k]
        if is_broken(signed, w, broken, k):
            continue
        j = U64(nbr[k])
        l = xi_len[k]
        d0, d1, d2 = bond_vector(y, U64(3) * j, yi0, yi1, yi2)
        r = bond_length(d0, d1, d2)
        if store_r:
            rbuf[k] = r
        g = dilatation_term(w, l, r)
        acc = fma(g, vol[j], acc)
        if checked and j >= r1:
            q = base + (j - r1)
            ov[q, 0] = fma(g, vi, ov[q, 0])
        else:
            theta[j] = fma(g, vi, theta[j])
    theta[i] += acc


@numba.njit(cache=True, inline="always", fastmath=FASTMATH, error_model="numpy")
def _dilatation_rows(r0, split, y, row_ptr, nbr, xi_len, broken, signed, vol, wt, theta, r1, ov,
                     base, rbuf, store_r):
    """Rows r0..r1 of one chunk: unchecked up to ``split``, then checked for overflow."""
    for i in range(r0, split):
        _dilatation_row(i, y, row_ptr, nbr, xi_len, broken, signed, vol, wt, theta, False,
                        r1, ov, base, rbuf, store_r)
    for i in range(split, r1):
        _dilatation_row(i, y, row_ptr, nbr, xi_len, broken, signed, vol, wt, theta, True,
                        r1, ov, base, rbuf, store_r)


@twin()
def dilatation_pairs(bonds, P, B, rbuf, store_r):
    """Pair-loop dilatation into ``P.theta``; with ``store_r`` also rbuf[k] = |y_j - y_i| of
    unbroken bonds."""
    row_ptr, nbr, xi_len, wt, broken = bonds.row_ptr, bonds.nbr, bonds.xi_len, bonds.weight, \
        bonds.broken
    y = P.y.reshape(P.y.size)  # flat view: 3 j + c indexing, no stride multiplications
    vol, m, theta = P.vol, P.m, P.theta
    cb, split, ov_ptr, ov = B.ptr, B.split, B.ov_ptr, B.ov
    signed = broken.shape[0] == 0
    C = cb.shape[0] - 1
    for c in prange(C):
        r0 = cb[c]
        r1 = U64(cb[c + 1])
        base = U64(ov_ptr[c])
        for p in range(r0, r1):
            theta[p] = 0.0
        for q in range(base, U64(ov_ptr[c + 1])):
            ov[q, 0] = 0.0
        # one copy of the row loop per flag combination, so that the flags are constants
        # inside the hot loop (no per-bond tests of them, fewer live registers)
        if signed:
            if store_r:
                _dilatation_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, True, vol, wt,
                                 theta, r1, ov, base, rbuf, True)
            else:
                _dilatation_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, True, vol, wt,
                                 theta, r1, ov, base, rbuf, False)
        elif store_r:
            _dilatation_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, False, vol, wt,
                             theta, r1, ov, base, rbuf, True)
        else:
            _dilatation_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, False, vol, wt,
                             theta, r1, ov, base, rbuf, False)
    for t in prange(C):
        add_overflow1(t, cb, ov_ptr, ov, 0, theta)
        for p in range(cb[t], cb[t + 1]):
            theta[p] = dilatation_of(theta[p], m[p])


@numba.njit(cache=True, inline="always", fastmath=FASTMATH, error_model="numpy")
def _forces_row(i, y, row_ptr, nbr, xi_len, broken, signed, vol, coef, aux, wt, nofail, f,
                checked, r1, ov, base, rbuf, use_r, rest, granular, sy, counted, lim, slip, y0,
                shear):
    """Row i of the pair-loop forces; returns the number of bonds it broke and, with
    ``granular``, the energy its crushed bonds dissipated (J, if ``counted``): a broken bond
    whose ``rest`` (p) is set (not NaN) is a crushed bond (:func:`~pdfem.pd.bonds.lps_law.
    crushed_bond`), and a bond breaking here becomes one (:func:`~pdfem.pd.bonds.lps_law.
    crushed_rest`), the energy its spring starts with counted as negative dissipation."""
    yi0 = y[3 * i]
    yi1 = y[3 * i + 1]
    yi2 = y[3 * i + 2]
    ai = coef[2 * i]
    bi = coef[2 * i + 1]
    hth = aux[2 * i]
    hfs = aux[2 * i + 1]
    vi = vol[i]
    can_i = nofail[i] == 0
    fx = 0.0
    fy = 0.0
    fz = 0.0
    nb = 0
    diss = 0.0
    rubs = slip.shape[0] > 0
    for k in range(U64(row_ptr[i]), U64(row_ptr[i + 1])):
        w = wt[k]
        if is_broken(signed, w, broken, k):
            if not granular:
                continue
            sb = rest[k]
            if sb != sb:  # NaN: broken for good
                continue
            j = U64(nbr[k])
            j3 = U64(3) * j
            j2 = U64(2) * j
            l = xi_len[k]
            d0, d1, d2 = bond_vector(y, j3, yi0, yi1, yi2)
            r = bond_length(d0, d1, d2)
            bij = bi + coef[j2 + U64(1)]
            g, p, dk = crushed_bond(bij, l, sb, sy, abs(w), r, vi * vol[j])
            if dk != 0.0:
                rest[k] = p
                diss += dk
            if rubs:
                fx, fy, fz, dk = apply_crushed_shear(k, i, j, j3, y, y0, slip, shear, g, bij, abs(w),
                                                r, d0, d1, d2, vi, vol[j], fx, fy, fz, checked,
                                                r1, ov, base, f)
                diss += dk
            if g == 0.0:
                continue
        else:
            j = U64(nbr[k])
            j3 = U64(3) * j
            j2 = U64(2) * j
            l = xi_len[k]
            d0, d1, d2 = bond_vector(y, j3, yi0, yi1, yi2)
            if use_r:
                r = rbuf[k]
            else:
                r = bond_length(d0, d1, d2)
            e = r - l
            if breaks(e, l, hth + aux[j2], hfs + aux[j2 + U64(1)], lim, can_i, nofail, j):
                mark_broken(signed, wt, w, broken, k)  # it still acts in this force evaluation
                if granular:
                    p = crushed_rest(e, l, sy)
                    rest[k] = p
                    diss -= crushed_bond_energy(bi + coef[j2 + U64(1)], l, rest[k], abs(w),
                                                r) * vi * vol[j]
                nb += 1
            g = pair_force_scalar(ai + coef[j2], bi + coef[j2 + U64(1)], l, e, w, r)
        fx, fy, fz = apply_pair_force(g, vol[j], vi, d0, d1, d2, fx, fy, fz, j, j3, checked, r1,
                                 ov, base, f)
    f[3 * i] += fx
    f[3 * i + 1] += fy
    f[3 * i + 2] += fz
    if not counted:
        diss = 0.0
    return nb, diss


@numba.njit(cache=True, inline="always", fastmath=FASTMATH, error_model="numpy")
def _forces_span(i0, i1, checked, y, row_ptr, nbr, xi_len, broken, signed, vol, coef, aux, wt,
                 nofail, f, r1, ov, base, rbuf, use_r, rest, granular, sy, owned, lim, slip, y0,
                 shear):
    """Rows i0..i1 with the overflow check ``checked``; bonds broken and energy dissipated."""
    nb = 0
    diss = 0.0
    every = owned.shape[0] == 0
    for i in range(i0, i1):
        n, d = _forces_row(i, y, row_ptr, nbr, xi_len, broken, signed, vol, coef, aux, wt,
                           nofail, f, checked, r1, ov, base, rbuf, use_r, rest, granular, sy,
                           every or owned[i] != 0, lim, slip, y0, shear)
        nb += n
        diss += d
    return nb, diss


@numba.njit(cache=True, inline="always", fastmath=FASTMATH, error_model="numpy")
def _forces_rows(r0, split, y, row_ptr, nbr, xi_len, broken, signed, vol, coef, aux, wt, nofail,
                 f, r1, ov, base, rbuf, use_r, rest, granular, sy, owned, lim, slip, y0, shear):
    """Rows r0..r1 of one chunk (unchecked up to ``split``); returns the bonds broken and the
    energy the crushed bonds of the ``owned`` rows (all if empty) dissipated, under a general
    failure law (:func:`forces_pairs_law`)."""
    n1, d1 = _forces_span(r0, split, False, y, row_ptr, nbr, xi_len, broken, signed, vol,
                          coef, aux, wt, nofail, f, r1, ov, base, rbuf, use_r, rest,
                          granular, sy, owned, lim, slip, y0, shear)
    n2, d2 = _forces_span(split, r1, True, y, row_ptr, nbr, xi_len, broken, signed, vol,
                          coef, aux, wt, nofail, f, r1, ov, base, rbuf, use_r, rest,
                          granular, sy, owned, lim, slip, y0, shear)
    return n1 + n2, d1 + d2


@numba.njit(cache=True, inline="always", fastmath=FASTMATH, error_model="numpy")
def _plain_row(i, y, row_ptr, nbr, xi_len, broken, signed, vol, coef, wt, s0, nofail, f,
                checked, r1, ov, base, rbuf, use_r):
    """Row i of the pair-loop forces under a plain critical stretch ``s0``; returns the number
    of bonds it broke."""
    yi0 = y[3 * i]
    yi1 = y[3 * i + 1]
    yi2 = y[3 * i + 2]
    ai = coef[2 * i]
    bi = coef[2 * i + 1]
    vi = vol[i]
    can_i = nofail[i] == 0
    fx = 0.0
    fy = 0.0
    fz = 0.0
    nb = 0
    for k in range(U64(row_ptr[i]), U64(row_ptr[i + 1])):
        w = wt[k]
        if is_broken(signed, w, broken, k):
            continue
        j = U64(nbr[k])
        j3 = U64(3) * j
        l = xi_len[k]
        d0, d1, d2 = bond_vector(y, j3, yi0, yi1, yi2)
        if use_r:
            r = rbuf[k]
        else:
            r = bond_length(d0, d1, d2)
        e = r - l
        if breaks_stretch(e, l, s0, can_i, nofail, j):   # it still acts in this force evaluation
            mark_broken(signed, wt, w, broken, k)
            nb += 1
        j2 = U64(2) * j
        g = pair_force_scalar(ai + coef[j2], bi + coef[j2 + U64(1)], l, e, w, r)
        fx, fy, fz = apply_pair_force(g, vol[j], vi, d0, d1, d2, fx, fy, fz, j, j3, checked, r1,
                                 ov, base, f)
    f[3 * i] += fx
    f[3 * i + 1] += fy
    f[3 * i + 2] += fz
    return nb


@numba.njit(cache=True, inline="always", fastmath=FASTMATH, error_model="numpy")
def _plain_rows(r0, split, y, row_ptr, nbr, xi_len, broken, signed, vol, coef, wt, s0, nofail,
                 f, r1, ov, base, rbuf, use_r):
    """Rows r0..r1 of one chunk (unchecked up to ``split``); returns the bonds broken."""
    nb = 0
    for i in range(r0, split):
        nb += _plain_row(i, y, row_ptr, nbr, xi_len, broken, signed, vol, coef, wt, s0,
                          nofail, f, False, r1, ov, base, rbuf, use_r)
    for i in range(split, r1):
        nb += _plain_row(i, y, row_ptr, nbr, xi_len, broken, signed, vol, coef, wt, s0,
                          nofail, f, True, r1, ov, base, rbuf, use_r)
    return nb


@twin(one_thread="parallel")
def forces_pairs(bonds, P, B, coef2, s0, rbuf, use_r):
    """Pair-loop force density into ``P.f`` and breaking under a plain critical stretch ``s0``
    (a bond breaks when its stretch exceeds s0); with ``use_r`` the bond lengths come from
    rbuf. Returns the bonds broken. The general failure laws run :func:`forces_pairs_law`."""
    row_ptr, nbr, xi_len, wt, broken = bonds.row_ptr, bonds.nbr, bonds.xi_len, bonds.weight, \
        bonds.broken
    y = P.y.reshape(P.y.size)  # flat views: 3 j + c indexing, no stride multiplications
    fout = P.f
    f = fout.reshape(fout.size)
    vol, nofail = P.vol, P.nofail
    coef = coef2.reshape(coef2.size)
    cb, split, ov_ptr, ov2, counts = B.ptr, B.split, B.ov_ptr, B.ov, B.counts
    ov = ov2.reshape(ov2.size)
    signed = broken.shape[0] == 0
    C = cb.shape[0] - 1
    for c in prange(C):
        r0 = cb[c]
        r1 = U64(cb[c + 1])
        base = U64(ov_ptr[c])
        for p in range(3 * r0, 3 * r1):
            f[p] = 0.0
        for q in range(U64(3) * base, U64(3) * U64(ov_ptr[c + 1])):
            ov[q] = 0.0
        # one copy of the row loop per flag combination (constants inside the hot loop)
        if signed:
            if use_r:
                nb = _plain_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, True, vol, coef,
                                  wt, s0, nofail, f, r1, ov, base, rbuf, True)
            else:
                nb = _plain_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, True, vol, coef,
                                  wt, s0, nofail, f, r1, ov, base, rbuf, False)
        elif use_r:
            nb = _plain_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, False, vol, coef,
                              wt, s0, nofail, f, r1, ov, base, rbuf, True)
        else:
            nb = _plain_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, False, vol, coef,
                              wt, s0, nofail, f, r1, ov, base, rbuf, False)
        counts[c] = nb
    for t in prange(C):
        add_overflow3(t, cb, ov_ptr, ov2, fout)
    total = 0
    for c in range(C):
        total += counts[c]
    return total


@twin(one_thread="parallel")
def forces_pairs_law(bonds, P, B, law, rbuf, use_r, granular):
    """:func:`forces_pairs` for a failure law with dilatation-dependent bounds, strength
    factors or crushed bonds (:mod:`pdfem.pd.failure.ice`): one copy of the row loop, with
    ``signed`` and ``use_r`` tested per bond (a separate kernel, compiled only when a body
    uses such a law, so that the plain loop's compile time stays what it was)."""
    row_ptr, nbr, xi_len, wt, broken = bonds.row_ptr, bonds.nbr, bonds.xi_len, bonds.weight, \
        bonds.broken
    y = P.y.reshape(P.y.size)  # flat views: 3 j + c indexing, no stride multiplications
    fout = P.f
    f = fout.reshape(fout.size)
    vol, nofail = P.vol, P.nofail
    coef = law.coef.reshape(law.coef.size)
    aux = law.aux.reshape(law.aux.size)
    rest, sy, owned, crush, lim = law.rest, law.crush_yield, law.owned, law.crush, law.lim
    slip, shear = law.slip.reshape(law.slip.size), law.shear
    y0 = law.y0.reshape(law.y0.size)
    cb, split, ov_ptr, ov2, counts = B.ptr, B.split, B.ov_ptr, B.ov, B.counts
    ov = ov2.reshape(ov2.size)
    signed = broken.shape[0] == 0
    C = cb.shape[0] - 1
    # each block's crushed-bond dissipation goes to a local array first: written through the
    # law tuple's array inside the parallel loop it was lost (0 on every multi-block body)
    dissipated = np.zeros(C)
    for c in prange(C):
        r0 = cb[c]
        r1 = U64(cb[c + 1])
        base = U64(ov_ptr[c])
        for p in range(3 * r0, 3 * r1):
            f[p] = 0.0
        for q in range(U64(3) * base, U64(3) * U64(ov_ptr[c + 1])):
            ov[q] = 0.0
        nb, dc = _forces_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, signed, vol, coef,
                              aux, wt, nofail, f, r1, ov, base, rbuf, use_r, rest, granular, sy,
                              owned, lim, slip, y0, shear)
        counts[c] = nb
        dissipated[c] = dc
    for c in range(C):
        crush[c] = dissipated[c]
    for t in prange(C):
        add_overflow3(t, cb, ov_ptr, ov2, fout)
    total = 0
    for c in range(C):
        total += counts[c]
    return total
