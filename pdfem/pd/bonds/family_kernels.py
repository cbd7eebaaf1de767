"""The per-particle full-family loop of the original PD algorithm: the reference LPS kernels.

Every particle loops over its whole family (:func:`pdfem.pd.bonds.family.build_family`), so every
bond is computed twice, once from each end, and each particle writes only its own entries (no
races, no chunking). The pair loops of :mod:`pdfem.pd.bonds.pair_loop` compute the same quantities
with the same formulas (:mod:`pdfem.pd.bonds.lps_law`) and bond weights; tests and the step benchmark
compare the two.
"""

from __future__ import annotations

import numba
from numba import prange

from pdfem.parallel.kernels import FASTMATH, fma
from pdfem.pd.bonds.chunk_kernels import U64
from pdfem.pd.bonds.lps_law import (
    bond_length,
    bond_vector,
    breaks,
    dilatation_of,
    dilatation_term,
    is_broken,
    mark_broken,
    pair_force_scalar,
)


@numba.njit(parallel=True, cache=True, fastmath=FASTMATH, error_model="numpy")
def dilatation_family_loop(y2, fam_ptr, fam_nbr, fam_bond, xi_len, broken, signed, vol, m, wt, theta):
    y = y2.reshape(y2.size)
    for i in prange(fam_ptr.shape[0] - 1):
        yi0 = y[3 * i]
        yi1 = y[3 * i + 1]
        yi2 = y[3 * i + 2]
        acc = 0.0
        for q in range(U64(fam_ptr[i]), U64(fam_ptr[i + 1])):
            k = U64(fam_bond[q])
            w = wt[k]
            if is_broken(signed, w, broken, k):
                continue
            j = U64(fam_nbr[q])
            l = xi_len[k]
            d0, d1, d2 = bond_vector(y, U64(3) * j, yi0, yi1, yi2)
            r = bond_length(d0, d1, d2)
            acc = fma(dilatation_term(w, l, r), vol[j], acc)
        theta[i] = dilatation_of(acc, m[i])


@numba.njit(parallel=True, cache=True, fastmath=FASTMATH, error_model="numpy")
def forces_family_loop(y2, fam_ptr, fam_nbr, fam_bond, xi_len, broken, signed, vol, coef2, wt, fout):
    y = y2.reshape(y2.size)
    coef = coef2.reshape(coef2.size)
    f = fout.reshape(fout.size)
    for i in prange(fam_ptr.shape[0] - 1):
        yi0 = y[3 * i]
        yi1 = y[3 * i + 1]
        yi2 = y[3 * i + 2]
        ai = coef[2 * i]
        bi = coef[2 * i + 1]
        fx = 0.0
        fy = 0.0
        fz = 0.0
        for q in range(U64(fam_ptr[i]), U64(fam_ptr[i + 1])):
            k = U64(fam_bond[q])
            w = wt[k]
            if is_broken(signed, w, broken, k):
                continue
            j = U64(fam_nbr[q])
            l = xi_len[k]
            d0, d1, d2 = bond_vector(y, U64(3) * j, yi0, yi1, yi2)
            r = bond_length(d0, d1, d2)
            e = r - l
            j2 = U64(2) * j
            g = pair_force_scalar(ai + coef[j2], bi + coef[j2 + U64(1)], l, e, w, r)
            g *= vol[j]
            fx = fma(g, d0, fx)
            fy = fma(g, d1, fy)
            fz = fma(g, d2, fz)
        f[3 * i] = fx
        f[3 * i + 1] = fy
        f[3 * i + 2] = fz


@numba.njit(cache=True)
def mark_family_breaks(y2, fam_ptr, fam_nbr, fam_bond, xi_len, broken, signed, wt, aux2, nofail, lim):
    """Mark the bonds that break at these positions (after the forces, in which they still
    acted), each once from its smaller-index end; the number marked."""
    y = y2.reshape(y2.size)
    aux = aux2.reshape(aux2.size)
    nb = 0
    for i in range(fam_ptr.shape[0] - 1):
        can_i = nofail[i] == 0
        hth = aux[2 * i]
        hfs = aux[2 * i + 1]
        for q in range(U64(fam_ptr[i]), U64(fam_ptr[i + 1])):
            j = U64(fam_nbr[q])
            if j <= U64(i):
                continue
            k = U64(fam_bond[q])
            w = wt[k]
            if is_broken(signed, w, broken, k):
                continue
            l = xi_len[k]
            d0, d1, d2 = bond_vector(y, U64(3) * j, y[3 * i], y[3 * i + 1], y[3 * i + 2])
            j2 = U64(2) * j
            if breaks(bond_length(d0, d1, d2) - l, l, hth + aux[j2], hfs + aux[j2 + U64(1)],
                      lim, can_i, nofail, j):
                mark_broken(signed, wt, w, broken, k)
                nb += 1
    return nb
