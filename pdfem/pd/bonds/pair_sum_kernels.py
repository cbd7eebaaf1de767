"""The pair loops that sum over bonds outside the time step: family sums, energy, damage.

Over the unique bonds i < j grouped by i (data layout: :mod:`pdfem.pd.bonds.pair_loop`), chunked
for race-free deterministic threading (:mod:`pdfem.pd.bonds.chunk_kernels`), every bond adding to both
its ends: :func:`family_sum_pairs` (weighted volume and the time-step sums),
:func:`energy_pairs` (strain energy density, :mod:`pdfem.pd.bonds.lps_law`) and
:func:`damage_pairs` (broken fraction of the initial bonds), and
:func:`contact_bond_energy_pairs` (the energy stored in crushed bonds). Float flags: ``FASTMATH`` of
:mod:`pdfem.parallel.kernels` (no FMA contraction, so the code compiled in this process and the
code loaded from numba's cache give the same bits). The kernels take the named tuples of
:mod:`pdfem.pd.bonds.data` and take their arrays out before the ``prange`` (numba loses writes
through tuples there: :mod:`pdfem.pd.bonds.pair_step_kernels`).
"""

from __future__ import annotations

import numba
from numba import prange

from pdfem.parallel.kernels import twin
from pdfem.pd.bonds.chunk_kernels import U64, add_overflow1
from pdfem.pd.bonds.lps_law import (bond_length, crushed_bond_energy, deviatoric_extension,
                              energy_density, is_broken)


@twin()
def family_sum_pairs(bonds, vol, mode, B, out):
    """out_i = sum_j g(|xi|) omega vol_j over all bonds, g = |xi|^2, 1/|xi|, |xi|, 1 (mode 0..3)."""
    row_ptr, nbr, xi_len, wt = bonds.row_ptr, bonds.nbr, bonds.xi_len, bonds.weight
    cb, ov_ptr, ov = B.ptr, B.ov_ptr, B.ov
    C = cb.shape[0] - 1
    for c in prange(C):
        r0 = cb[c]
        r1 = U64(cb[c + 1])
        base = U64(ov_ptr[c])
        for p in range(r0, r1):
            out[p] = 0.0
        for q in range(base, U64(ov_ptr[c + 1])):
            ov[q, 0] = 0.0
        for i in range(r0, r1):
            vi = vol[i]
            acc = 0.0
            for k in range(U64(row_ptr[i]), U64(row_ptr[i + 1])):
                j = U64(nbr[k])
                l = xi_len[k]
                if mode == 0:
                    g = l * l
                elif mode == 1:
                    g = 1.0 / l
                elif mode == 2:
                    g = l
                else:
                    g = 1.0
                g *= abs(wt[k])  # all initial bonds (a negative weight marks a broken one)
                acc += g * vol[j]
                if j < r1:
                    out[j] += g * vi
                else:
                    ov[base + (j - r1), 0] += g * vi
            out[i] += acc
    for t in prange(C):
        add_overflow1(t, cb, ov_ptr, ov, 0, out)


@twin()
def energy_pairs(bonds, P, K, mu, B, W, rbuf, use_r):
    """W_i = K theta_i^2 / 2 + (15 mu / (2 m_i)) sum_j omega e_d^2 V_j over unbroken bonds;
    with ``use_r`` their current lengths are read from ``rbuf`` (kept by the step's
    dilatation pass at these positions: the same bits as taking them again) instead of
    taken from the positions."""
    row_ptr, nbr, xi_len, wt, broken = bonds.row_ptr, bonds.nbr, bonds.xi_len, bonds.weight, \
        bonds.broken
    signed = broken.shape[0] == 0
    y, vol, m, theta = P.y, P.vol, P.m, P.theta
    cb, ov_ptr, ov = B.ptr, B.ov_ptr, B.ov
    C = cb.shape[0] - 1
    for c in prange(C):
        r0 = cb[c]
        r1 = U64(cb[c + 1])
        base = U64(ov_ptr[c])
        for p in range(r0, r1):
            W[p] = 0.0
        for q in range(base, U64(ov_ptr[c + 1])):
            ov[q, 0] = 0.0
        for i in range(r0, r1):
            ti = theta[i] / 3.0
            vi = vol[i]
            acc = 0.0
            for k in range(U64(row_ptr[i]), U64(row_ptr[i + 1])):
                b = wt[k]
                if is_broken(signed, b, broken, k):
                    continue
                j = U64(nbr[k])
                l = xi_len[k]
                if use_r:
                    e = rbuf[k] - l
                else:
                    e = bond_length(y[j, 0] - y[i, 0], y[j, 1] - y[i, 1], y[j, 2] - y[i, 2]) - l
                edi = deviatoric_extension(e, ti, l)
                edj = deviatoric_extension(e, theta[j] / 3.0, l)
                acc += edi * edi * b * vol[j]
                g = edj * edj * b * vi
                if j < r1:
                    W[j] += g
                else:
                    ov[base + (j - r1), 0] += g
            W[i] += acc
    for t in prange(C):
        add_overflow1(t, cb, ov_ptr, ov, 0, W)
        for p in range(cb[t], cb[t + 1]):
            W[p] = energy_density(K, mu, theta[p], W[p], m[p])


@twin(fastmath=False)
def damage_pairs(bonds, B, nb, deg):
    """nb_i = broken fraction of particle i's initial bonds (deg: scratch for the degrees)."""
    row_ptr, nbr, wt, broken = bonds.row_ptr, bonds.nbr, bonds.weight, bonds.broken
    signed = broken.shape[0] == 0
    cb, ov_ptr, ov = B.ptr, B.ov_ptr, B.ov
    C = cb.shape[0] - 1
    for c in prange(C):
        r0 = cb[c]
        r1 = U64(cb[c + 1])
        base = U64(ov_ptr[c])
        for p in range(r0, r1):
            nb[p] = 0.0
            deg[p] = 0.0
        for q in range(base, U64(ov_ptr[c + 1])):
            ov[q, 0] = 0.0
            ov[q, 1] = 0.0
        for i in range(r0, r1):
            cnt = 0.0
            for k in range(U64(row_ptr[i]), U64(row_ptr[i + 1])):
                j = U64(nbr[k])
                if signed:
                    b = 1.0 if wt[k] < 0.0 else 0.0
                else:
                    b = 1.0 if broken[k] != 0 else 0.0
                cnt += b
                if j < r1:
                    nb[j] += b
                    deg[j] += 1.0
                else:
                    ov[base + (j - r1), 0] += b
                    ov[base + (j - r1), 1] += 1.0
            nb[i] += cnt
            deg[i] += row_ptr[i + 1] - row_ptr[i]
    for t in prange(C):
        add_overflow1(t, cb, ov_ptr, ov, 0, nb)
        add_overflow1(t, cb, ov_ptr, ov, 1, deg)
        for p in range(cb[t], cb[t + 1]):
            nb[p] = nb[p] / deg[p] if deg[p] > 0.0 else 0.0


@numba.njit(cache=True)
def contact_bond_energy_pairs(bonds, P, rest, mu, owned, slip, kappa):
    """Total energy (J) stored in the crushed bonds (:func:`~pdfem.pd.bonds.lps_law.
    crushed_bond_energy`, ``rest`` not NaN) in the rows i with ``owned[i]`` (all rows if
    ``owned`` is empty), summed serially in bond order; with ``slip`` (flat (3P,), m) also
    that of their shear springs, kappa b w V_i V_j |s|^2 / 2 (:mod:`pdfem.pd.failure.crushed_shear`)."""
    row_ptr, nbr, xi_len, wt, broken = bonds.row_ptr, bonds.nbr, bonds.xi_len, bonds.weight, \
        bonds.broken
    signed = broken.shape[0] == 0
    y, vol, m = P.y, P.vol, P.m
    total = 0.0
    c = 15.0 * mu
    every = owned.shape[0] == 0
    sheared = slip.shape[0] > 0
    for i in range(row_ptr.shape[0] - 1):
        if not every and not owned[i]:
            continue
        bi = c / m[i] if m[i] > 0.0 else 0.0
        for k in range(U64(row_ptr[i]), U64(row_ptr[i + 1])):
            w = wt[k]
            if not is_broken(signed, w, broken, k):
                continue
            sb = rest[k]
            if sb != sb:
                continue
            j = U64(nbr[k])
            bj = c / m[j] if m[j] > 0.0 else 0.0
            r = bond_length(y[j, 0] - y[i, 0], y[j, 1] - y[i, 1], y[j, 2] - y[i, 2])
            e = crushed_bond_energy(bi + bj, xi_len[k], sb, abs(w), r)
            if sheared:
                k3 = U64(3) * k
                s2 = ((1.0 * slip[k3]) ** 2 + (1.0 * slip[k3 + U64(1)]) ** 2
                      + (1.0 * slip[k3 + U64(2)]) ** 2)
                e += 0.5 * kappa * (bi + bj) * abs(w) * s2
            total += e * vol[i] * vol[j]
    return total
