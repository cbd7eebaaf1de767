"""Numba pair-loop kernels of the 3-D linear peridynamic solid (LPS, Silling et al. 2007).

Data layout (shared with the rest of pdfem):

- ``y`` (N, 3) float64 current positions (m); ``vol`` (N,) float64 particle volumes (m^3);
- unique bonds i < j grouped by i (CSR, the "particle-pair method"): ``row_ptr`` int64 (N+1,),
  ``nbr`` int32 (P,); bond k joins i and ``nbr[k]`` for k in ``row_ptr[i]:row_ptr[i+1]``;
- ``xi_len`` (P,) float64 reference bond lengths (m);
- ``weight`` (P,) float32 bond weights omega = w beta, the influence function times the
  partial-volume factor (:mod:`pdfem.pd.influence`);
- ``broken`` (P,) uint8, 1 = broken for good; or :data:`SIGNED` (an empty array), which says
  that a bond is broken when its weight is negative (the bond-break check then negates the
  weight): that is how :class:`pdfem.pd.body.IceBody` stores its bonds, 16 bytes per pair
  (int32 partner, float64 length, float32 signed weight) instead of 17;
- ``nofail`` (N,) uint8, 1 = bonds touching this particle never break.

Per particle i with family j (e = |y_j - y_i| - |xi|, every family sum weighs member j by
``omega V_j``)::

    m_i     = sum_j omega |xi|^2 V_j                       (all initial bonds)
    theta_i = (3 / m_i) sum_j omega |xi| e V_j             (unbroken bonds)
    t_ij    = (3 K theta_i / m_i) |xi| + (15 mu / m_i) e_d,   e_d = e - theta_i |xi| / 3
    L_i     = sum_j (t_ij + t_ji) omega V_j (y_j - y_i) / |y_j - y_i|   (force density, N/m^3)
    W_i     = K theta_i^2 / 2 + (15 mu / (2 m_i)) sum_j omega e_d^2 V_j (energy density, J/m^3)

so that the total strain energy sum_i W_i V_i has gradient -V_i L_i with respect to y_i.

A step computes the dilatation first, then forces with the break check: bond k breaks when its
stretch e / |xi| exceeds ``s0`` and neither end has ``nofail``; a bond breaking in the force
call contributes no force there and is marked broken (the dilatation of the same step still
used it). Damage is the broken fraction of a particle's initial bonds.

The loops are chunked for race-free, deterministic threading (:mod:`pdfem.pd.workspace`).
:func:`dilatation_and_forces` is the time loop's entry point: the two passes of a step, with
the bond lengths of the first pass kept for the second (8 bytes per pair of scratch).
Index arithmetic is unsigned (``U64``) inside the pair loops: numba then emits no
negative-index wraparound code for the gathers and scatters, which is a large part of the
instruction count of these short loop bodies.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import prange

from pdfem.pd.workspace import (
    FASTMATH,
    U64,
    PairWorkspace,
    add_overflow1,
    add_overflow3,
    c_contiguous,
    twin,
    workspace_for,
)

_NO_R = np.zeros(0)  # stands for "no bond-length buffer" (read-only by convention)

#: Pass as ``broken`` to mean "bond k is broken iff weight[k] < 0" (read-only by convention).
SIGNED = np.zeros(0, dtype=np.uint8)


def check_broken(broken: np.ndarray, per_pair: np.ndarray) -> bool:
    """True if ``broken`` is :data:`SIGNED` (broken = negative weight); False for a (P,) uint8
    flag array shaped like ``per_pair``; ValueError otherwise."""
    if not isinstance(broken, np.ndarray) or broken.dtype != np.uint8:
        raise ValueError("broken must be a uint8 array (or pdfem.pd.pair_kernels.SIGNED)")
    if broken.shape[0] == 0 and per_pair.shape[0] != 0:
        return True
    if broken.shape != per_pair.shape:
        raise ValueError(f"broken must have one flag per pair (shape {per_pair.shape}), "
                         f"got {broken.shape}")
    return False


def signed_weights(weight: np.ndarray, broken: np.ndarray) -> np.ndarray:
    """float32 weights with the broken bonds (``broken`` != 0) negated: the :data:`SIGNED` form."""
    out = np.abs(np.asarray(weight, dtype=np.float32))
    np.negative(out, out=out, where=np.asarray(broken) != 0)
    return out


def broken_flags(weight: np.ndarray) -> np.ndarray:
    """(P,) uint8 broken flags (1 where the weight is negative) of :data:`SIGNED` weights."""
    return (np.asarray(weight) < 0).view(np.uint8)


def check_weight(weight: np.ndarray, per_pair: np.ndarray) -> np.ndarray:
    """``weight`` itself if it is a C-contiguous float32 array shaped like ``per_pair`` (P,)."""
    if (not isinstance(weight, np.ndarray) or weight.dtype != np.float32
            or weight.shape != per_pair.shape or not weight.flags.c_contiguous):
        raise ValueError(
            "weight must be a C-contiguous float32 array with one bond weight per pair "
            f"(shape {per_pair.shape}); build it with pdfem.pd.influence.bond_weights"
        )
    return weight


@twin()
def _family_sum_pairs(row_ptr, nbr, xi_len, vol, wt, mode, cb, ov_ptr, ov, out):
    """out_i = sum_j g(|xi|) omega vol_j over all bonds, g = |xi|^2, 1/|xi|, |xi|, 1 (mode 0..3)."""
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
        if signed:
            if w < 0.0:
                continue
        elif broken[k] != 0:
            continue
        j = U64(nbr[k])
        j3 = U64(3) * j
        l = xi_len[k]
        d0 = y[j3] - yi0
        d1 = y[j3 + U64(1)] - yi1
        d2 = y[j3 + U64(2)] - yi2
        r = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if store_r:
            rbuf[k] = r
        g = w * l * (r - l)
        acc += g * vol[j]
        if checked and j >= r1:
            ov[base + (j - r1), 0] += g * vi
        else:
            theta[j] += g * vi
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
def _dilatation_pairs(y2, row_ptr, nbr, xi_len, broken, signed, vol, m, wt, cb, split, ov_ptr,
                      ov, theta, rbuf, store_r):
    """Pair-loop dilatation; with ``store_r`` also rbuf[k] = |y_j - y_i| of unbroken bonds."""
    y = y2.reshape(y2.size)  # flat view: 3 j + c indexing, no stride multiplications
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
            theta[p] = 3.0 * theta[p] / m[p] if m[p] > 0.0 else 0.0


@twin(fastmath=False)
def force_coefficients(m, theta, K, mu, coef):
    """coef[:, 0] = theta (3K - 5mu) / m, coef[:, 1] = 15 mu / m (0 where m = 0)."""
    c1 = 3.0 * K - 5.0 * mu
    c2 = 15.0 * mu
    for p in prange(m.shape[0]):
        if m[p] > 0.0:
            im = 1.0 / m[p]
            coef[p, 0] = theta[p] * c1 * im
            coef[p, 1] = c2 * im
        else:
            coef[p, 0] = 0.0
            coef[p, 1] = 0.0


@numba.njit(cache=True, inline="always", fastmath=FASTMATH, error_model="numpy")
def _forces_row(i, y, row_ptr, nbr, xi_len, broken, signed, vol, coef, wt, s0, nofail, f,
                checked, r1, ov, base, rbuf, use_r):
    """Row i of the pair-loop forces; returns the number of bonds it broke."""
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
        if signed:
            if w < 0.0:
                continue
        elif broken[k] != 0:
            continue
        j = U64(nbr[k])
        j3 = U64(3) * j
        l = xi_len[k]
        d0 = y[j3] - yi0
        d1 = y[j3 + U64(1)] - yi1
        d2 = y[j3 + U64(2)] - yi2
        if use_r:
            r = rbuf[k]
        else:
            r = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        e = r - l
        if e > s0 * l and can_i and nofail[j] == 0:
            if signed:
                wt[k] = -w
            else:
                broken[k] = 1
            nb += 1
            continue
        j2 = U64(2) * j
        g = ((ai + coef[j2]) * l + (bi + coef[j2 + U64(1)]) * e) * w / r
        gi = g * vol[j]
        fx += gi * d0
        fy += gi * d1
        fz += gi * d2
        gj = g * vi
        if checked and j >= r1:
            q = U64(3) * (base + (j - r1))
            ov[q] -= gj * d0
            ov[q + U64(1)] -= gj * d1
            ov[q + U64(2)] -= gj * d2
        else:
            f[j3] -= gj * d0
            f[j3 + U64(1)] -= gj * d1
            f[j3 + U64(2)] -= gj * d2
    f[3 * i] += fx
    f[3 * i + 1] += fy
    f[3 * i + 2] += fz
    return nb


@numba.njit(cache=True, inline="always", fastmath=FASTMATH, error_model="numpy")
def _forces_rows(r0, split, y, row_ptr, nbr, xi_len, broken, signed, vol, coef, wt, s0, nofail,
                 f, r1, ov, base, rbuf, use_r):
    """Rows r0..r1 of one chunk (unchecked up to ``split``); returns the bonds broken."""
    nb = 0
    for i in range(r0, split):
        nb += _forces_row(i, y, row_ptr, nbr, xi_len, broken, signed, vol, coef, wt, s0,
                          nofail, f, False, r1, ov, base, rbuf, use_r)
    for i in range(split, r1):
        nb += _forces_row(i, y, row_ptr, nbr, xi_len, broken, signed, vol, coef, wt, s0,
                          nofail, f, True, r1, ov, base, rbuf, use_r)
    return nb


@twin()
def _forces_pairs(y2, row_ptr, nbr, xi_len, broken, signed, vol, coef2, wt, s0, nofail,
                  cb, split, ov_ptr, ov2, counts, fout, rbuf, use_r):
    """Pair-loop force density and breaking; with ``use_r`` the bond lengths come from rbuf."""
    y = y2.reshape(y2.size)  # flat views: 3 j + c indexing, no stride multiplications
    coef = coef2.reshape(coef2.size)
    f = fout.reshape(fout.size)
    ov = ov2.reshape(ov2.size)
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
                nb = _forces_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, True, vol, coef,
                                  wt, s0, nofail, f, r1, ov, base, rbuf, True)
            else:
                nb = _forces_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, True, vol, coef,
                                  wt, s0, nofail, f, r1, ov, base, rbuf, False)
        elif use_r:
            nb = _forces_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, False, vol, coef,
                              wt, s0, nofail, f, r1, ov, base, rbuf, True)
        else:
            nb = _forces_rows(r0, split[c], y, row_ptr, nbr, xi_len, broken, False, vol, coef,
                              wt, s0, nofail, f, r1, ov, base, rbuf, False)
        counts[c] = nb
    for t in prange(C):
        add_overflow3(t, cb, ov_ptr, ov2, fout)
    total = 0
    for c in range(C):
        total += counts[c]
    return total


@twin()
def _energy_pairs(y, row_ptr, nbr, xi_len, broken, signed, vol, m, theta, K, mu, wt,
                  cb, ov_ptr, ov, W):
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
                if signed:
                    if b < 0.0:
                        continue
                elif broken[k] != 0:
                    continue
                j = U64(nbr[k])
                l = xi_len[k]
                d0 = y[j, 0] - y[i, 0]
                d1 = y[j, 1] - y[i, 1]
                d2 = y[j, 2] - y[i, 2]
                e = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2) - l
                edi = e - ti * l
                edj = e - theta[j] / 3.0 * l
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
            s = 7.5 * mu * W[p] / m[p] if m[p] > 0.0 else 0.0
            W[p] = 0.5 * K * theta[p] * theta[p] + s


@twin(fastmath=False)
def _damage_pairs(row_ptr, nbr, broken, signed, wt, cb, ov_ptr, ov, nb, deg):
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


# --------------------------------------------------------------------------- public API


def family_sum(
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    values: np.ndarray,
    mode: int,
    ws: PairWorkspace | None = None,
) -> np.ndarray:
    """Family sums over all initial bonds: out_i = sum_j g(|xi|) omega values_j (both ends).

    Parameters
    ----------
    row_ptr, nbr, xi_len, weight
        Pair list, reference bond lengths (m) and bond weights (float32).
    values
        (N,) float64 per-particle values (volumes, or volumes times a factor).
    mode
        g = |xi|^2, 1/|xi|, |xi|, 1 for mode 0, 1, 2, 3.
    ws
        Optional :class:`PairWorkspace` for this pair list.

    Returns
    -------
    ndarray
        (N,) float64 sums.
    """
    ws = workspace_for(ws, row_ptr, nbr)
    out = np.empty(ws.n)
    _family_sum_pairs(ws.parallel, row_ptr, nbr, xi_len, np.ascontiguousarray(values, np.float64),
                      check_weight(weight, nbr), int(mode), ws.chunk_ptr, ws.ov_ptr, ws.ov, out)
    return out


def weighted_volume(
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    vol: np.ndarray,
    ws: PairWorkspace | None = None,
) -> np.ndarray:
    """Weighted volume m_i = sum_j omega |xi|^2 V_j over all initial bonds.

    Parameters
    ----------
    row_ptr, nbr
        CSR unique pairs i < j (int64 (N+1,), int32 (P,)).
    xi_len
        (P,) reference bond lengths (m).
    weight
        (P,) float32 bond weights omega (:func:`pdfem.pd.influence.bond_weights`).
    vol
        (N,) particle volumes (m^3).
    ws
        Optional :class:`PairWorkspace` for this pair list.

    Returns
    -------
    ndarray
        (N,) float64 weighted volume (m^5).
    """
    return family_sum(row_ptr, nbr, xi_len, weight, vol, 0, ws)


def dilatation(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    theta_out: np.ndarray,
    ws: PairWorkspace | None = None,
) -> None:
    """Dilatation theta_i = (3 / m_i) sum_j omega |xi| e V_j over unbroken bonds (pair loop).

    Parameters
    ----------
    y
        (N, 3) current positions (m).
    row_ptr, nbr, xi_len, weight, broken
        Pair list, reference lengths (m), bond weights (float32) and broken flags (uint8, or
        :data:`SIGNED`: broken = negative weight).
    vol, m
        (N,) volumes (m^3) and weighted volumes (m^5, :func:`weighted_volume`).
    theta_out
        (N,) float64, overwritten with the dilatation (dimensionless); 0 where m = 0.
    ws
        Optional :class:`PairWorkspace` for this pair list.
    """
    ws = workspace_for(ws, row_ptr, nbr)
    _dilatation_pairs(ws.parallel, c_contiguous(y, "y"), row_ptr, nbr, xi_len, broken,
                      check_broken(broken, nbr), vol, m, check_weight(weight, nbr), ws.chunk_ptr,
                      ws.split, ws.ov_ptr, ws.ov,
                      theta_out, _NO_R, False)


def forces(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    theta: np.ndarray,
    K: float,
    mu: float,
    s0: float,
    nofail: np.ndarray,
    f_out: np.ndarray,
    ws: PairWorkspace | None = None,
) -> int:
    """LPS force density with the bond-break check (pair loop).

    A bond with stretch ``e / |xi| > s0`` whose ends both lack ``nofail`` breaks here: it is
    marked in ``broken`` and contributes no force. Already broken bonds are skipped.

    Parameters
    ----------
    y
        (N, 3) current positions (m).
    row_ptr, nbr, xi_len, weight
        Pair list, reference bond lengths (m) and bond weights (float32).
    broken
        (P,) uint8, updated in place; or :data:`SIGNED`, and then a bond that breaks gets its
        ``weight`` negated in place.
    vol, m, theta
        (N,) volumes (m^3), weighted volumes (m^5) and dilatations of this step.
    K, mu
        Bulk and shear modulus (Pa).
    s0
        Critical stretch (``inf``: no breaking).
    nofail
        (N,) uint8, 1 = the particle's bonds never break.
    f_out
        (N, 3) float64, overwritten with the force density L_i (N/m^3).
    ws
        Optional :class:`PairWorkspace` for this pair list.

    Returns
    -------
    int
        Number of bonds broken in this call.
    """
    ws = workspace_for(ws, row_ptr, nbr)
    force_coefficients(ws.parallel_particles, m, theta, K, mu, ws.coef)
    return int(_forces_pairs(ws.parallel, c_contiguous(y, "y"), row_ptr, nbr, xi_len, broken,
                             check_broken(broken, nbr), vol,
                             ws.coef, check_weight(weight, nbr), float(s0), nofail, ws.chunk_ptr,
                             ws.split, ws.ov_ptr, ws.ov, ws.counts, c_contiguous(f_out, "f_out"),
                             _NO_R, False))


def dilatation_and_forces(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    K: float,
    mu: float,
    s0: float,
    nofail: np.ndarray,
    theta_out: np.ndarray,
    f_out: np.ndarray,
    ws: PairWorkspace,
    between=None,
) -> int:
    """One OSB step's internal forces: :func:`dilatation`, then :func:`forces` (pair loops).

    Bit-identical to the two calls, but faster: the dilatation pass stores every unbroken
    bond's current length in the workspace (``ws.bond_length``, float64 (P,), allocated on first
    use: 8 bytes per pair) and the force pass reads it instead of taking a second square root
    (about 30 % of the force pass). A workspace built with ``keep_bond_length=False`` skips that
    buffer (for the largest bodies, where memory counts more) and takes the square root twice.

    Parameters are those of :func:`dilatation` and :func:`forces`; ``theta_out`` (N,) and
    ``f_out`` (N, 3) are overwritten; ``ws`` is required. ``between``, if given, is called with
    ``theta_out`` between the two passes (an MPI rank's body exchanges its halo's dilatations
    there).

    Returns
    -------
    int
        Number of bonds broken in this call.
    """
    ws.check(row_ptr, nbr)
    rbuf = ws.bond_length_buffer() if ws.keep_bond_length else _NO_R
    keep = rbuf.shape[0] > 0
    wt = check_weight(weight, nbr)
    signed = check_broken(broken, nbr)
    _dilatation_pairs(ws.parallel, c_contiguous(y, "y"), row_ptr, nbr, xi_len, broken, signed, vol,
                      m, wt, ws.chunk_ptr, ws.split, ws.ov_ptr, ws.ov, theta_out, rbuf, keep)
    if between is not None:
        between(theta_out)
    force_coefficients(ws.parallel_particles, m, theta_out, K, mu, ws.coef)
    return int(_forces_pairs(ws.parallel, y, row_ptr, nbr, xi_len, broken, signed, vol, ws.coef, wt,
                             float(s0), nofail, ws.chunk_ptr, ws.split, ws.ov_ptr, ws.ov,
                             ws.counts, c_contiguous(f_out, "f_out"), rbuf, keep))


def strain_energy(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    theta: np.ndarray,
    K: float,
    mu: float,
    ws: PairWorkspace | None = None,
) -> np.ndarray:
    """Strain energy density W_i = K theta_i^2 / 2 + (15 mu / (2 m_i)) sum_j omega e_d^2 V_j.

    Parameters are as in :func:`forces` (``theta`` from :func:`dilatation` for the same ``y``).

    Returns
    -------
    ndarray
        (N,) float64 energy density (J/m^3); the total strain energy is ``(W * vol).sum()``.
    """
    ws = workspace_for(ws, row_ptr, nbr)
    W = np.empty(ws.n)
    _energy_pairs(ws.parallel, c_contiguous(y, "y"), row_ptr, nbr, xi_len, broken,
                  check_broken(broken, nbr), vol, m, theta,
                  float(K), float(mu), check_weight(weight, nbr), ws.chunk_ptr, ws.ov_ptr, ws.ov,
                  W)
    return W


def damage(
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    broken: np.ndarray,
    n: int,
    ws: PairWorkspace | None = None,
    weight: np.ndarray | None = None,
) -> np.ndarray:
    """Damage: the broken fraction of each particle's initial bonds (0 for a particle without).

    Parameters
    ----------
    row_ptr, nbr, broken
        Pair list and broken flags (or :data:`SIGNED`); every pair counts for both its ends.
    n
        Number of particles N.
    ws
        Optional :class:`PairWorkspace` for this pair list.
    weight
        The signed float32 bond weights; required (and only read) with ``broken=SIGNED``.

    Returns
    -------
    ndarray
        (N,) float64 in [0, 1].
    """
    if row_ptr.shape[0] != n + 1:
        raise ValueError(f"row_ptr must have n + 1 = {n + 1} entries, got {row_ptr.shape[0]}")
    ws = workspace_for(ws, row_ptr, nbr)
    out = np.empty(n)
    deg = np.empty(n)
    if weight is None:
        weight = np.zeros(0, dtype=np.float32)
    signed = check_broken(broken, nbr)
    if signed:
        check_weight(weight, nbr)
    _damage_pairs(ws.parallel, row_ptr, nbr, broken, signed, weight, ws.chunk_ptr, ws.ov_ptr,
                  ws.ov, out, deg)
    return out


