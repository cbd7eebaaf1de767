"""Numba kernels of the 3-D linear peridynamic solid (LPS, Silling et al. 2007).

Data layout (shared with the rest of pdfem):

- ``y`` (N, 3) float64 current positions (m); ``vol`` (N,) float64 particle volumes (m^3);
- unique bonds i < j grouped by i (CSR, the "particle-pair method"): ``row_ptr`` int64 (N+1,),
  ``nbr`` int32 (P,); bond k joins i and ``nbr[k]`` for k in ``row_ptr[i]:row_ptr[i+1]``;
- ``xi_len`` (P,) float64 reference bond lengths (m); ``broken`` (P,) uint8, 1 = broken for good;
- ``nofail`` (N,) uint8, 1 = bonds touching this particle never break.

Influence function w = 1. Every family sum over j weighs member j by ``beta * vol[j]``, where
beta is the partial-volume factor of the bond (Madenci & Oterkus 2014)::

    beta = 1                               if |xi| <= delta - dx/2
         = (delta + dx/2 - |xi|) / dx      otherwise (bonds exist up to delta: beta >= 1/2)

computed on the fly from ``xi_len`` (as ``min(1, (delta + dx/2 - |xi|) / dx)``).

Per particle i with family j (e = |y_j - y_i| - |xi|)::

    m_i     = sum_j |xi|^2 beta V_j                       (all initial bonds)
    theta_i = (3 / m_i) sum_j |xi| e beta V_j             (unbroken bonds)
    t_ij    = (3 K theta_i / m_i) |xi| + (15 mu / m_i) e_d,   e_d = e - theta_i |xi| / 3
    L_i     = sum_j (t_ij + t_ji) beta V_j (y_j - y_i) / |y_j - y_i|     (force density, N/m^3)
    W_i     = K theta_i^2 / 2 + (15 mu / (2 m_i)) sum_j e_d^2 beta V_j   (energy density, J/m^3)

so that the total strain energy sum_i W_i V_i has gradient -V_i L_i with respect to y_i.

A step computes the dilatation first, then forces with the break check: bond k breaks when its
stretch e / |xi| exceeds ``s0`` and neither end has ``nofail``; a bond breaking in the force
call contributes no force there and is marked broken (the dilatation of the same step still
used it). Damage is the broken fraction of a particle's initial bonds.

Parallel pair loops without races: the particles (rows) are cut into C chunks of equal pair
count (:class:`PairWorkspace`); a ``prange`` over chunks accumulates the i side of each row in
registers and writes the j side directly into the output when j lies in the chunk's own rows
and otherwise into the chunk's overflow buffer (pairs point forwards, j > i, so only later rows
can be hit from outside). A second ``prange`` over chunks adds the overflow buffers of the
earlier chunks in fixed chunk order. The result is therefore bit-identical from run to run for a
given chunk count (by default the number of numba threads). Small pair lists (fewer than
``SERIAL_BELOW_PAIRS``) get one chunk and run a serial build of the same kernel.

:func:`dilatation_and_forces` is the time loop's entry point: the two passes of a step, with
the bond lengths of the first pass kept for the second (8 bytes per pair of scratch).

The per-particle full-family loop of the original PD algorithm (every bond computed twice, see
:mod:`pdfem.pd.family`) is kept in :func:`dilatation_family` and :func:`forces_family` as the
reference for tests and benchmarks.
"""

from __future__ import annotations

import math
import types

import numba
import numpy as np
from numba import prange

_FM = {"nsz", "arcp", "contract", "reassoc"}
_U = np.uint64
_NO_R = np.zeros(0)  # stands for "no bond-length buffer" (read-only by convention)

# Below these sizes the kernels run their serial build: a parallel region costs more than the
# work, and a lot more when the machine is oversubscribed (the threads wait at a barrier for a
# descheduled peer).
SERIAL_BELOW_PAIRS = 50_000
SERIAL_BELOW_PARTICLES = 20_000


class _Twin:
    """A kernel compiled twice: thread-parallel (``prange``) and serial (``prange`` = range).

    Called as ``kernel(parallel, *args)``. The serial build is a clone of the function under
    another qualified name, so both builds have their own on-disk cache entries.
    """

    __slots__ = ("par", "ser")

    def __init__(self, pyfunc, fastmath):
        fm = _FM if fastmath else False
        self.par = numba.njit(parallel=True, cache=True, fastmath=fm, error_model="numpy")(pyfunc)
        clone = types.FunctionType(pyfunc.__code__, pyfunc.__globals__, pyfunc.__name__ + "_serial",
                                   pyfunc.__defaults__, pyfunc.__closure__)
        clone.__qualname__ = pyfunc.__qualname__ + "_serial"
        clone.__doc__ = pyfunc.__doc__
        self.ser = numba.njit(cache=True, fastmath=fm, error_model="numpy")(clone)

    def __call__(self, parallel, *args):
        return (self.par if parallel else self.ser)(*args)


def _twin(fastmath=True):
    return lambda pyfunc: _Twin(pyfunc, fastmath)


# --------------------------------------------------------------------------- helpers


@numba.njit(cache=True, inline="always")
def _beta(l, hi, inv_dx):
    """Partial-volume factor; ``hi = delta + dx/2``."""
    return min(1.0, (hi - l) * inv_dx)


@numba.njit(cache=True)
def _add_overflow1(t, cb, ov_ptr, ov, col, out):
    """Add the overflow of chunks 0..t-1 (in that order) into the rows of chunk t."""
    r0 = cb[t]
    r1 = cb[t + 1]
    for c in range(t):
        s = cb[c + 1]
        base = ov_ptr[c]
        e = s + (ov_ptr[c + 1] - base)
        lo = max(s, r0)
        hi = min(e, r1)
        for p in range(lo, hi):
            out[p] += ov[base + p - s, col]


@numba.njit(cache=True)
def _add_overflow3(t, cb, ov_ptr, ov, out):
    r0 = cb[t]
    r1 = cb[t + 1]
    for c in range(t):
        s = cb[c + 1]
        base = ov_ptr[c]
        e = s + (ov_ptr[c + 1] - base)
        lo = max(s, r0)
        hi = min(e, r1)
        for p in range(lo, hi):
            q = base + p - s
            out[p, 0] += ov[q, 0]
            out[p, 1] += ov[q, 1]
            out[p, 2] += ov[q, 2]


@numba.njit(cache=True)
def _pairs_forward(row_ptr, nbr):
    """True when every pair of row i has i < nbr[k] < N (what the chunked loops rely on)."""
    n = row_ptr.shape[0] - 1
    for i in range(n):
        if row_ptr[i + 1] < row_ptr[i]:
            return False
        for k in range(row_ptr[i], row_ptr[i + 1]):
            j = nbr[k]
            if j <= i or j >= n:
                return False
    return True


@numba.njit(cache=True)
def _chunk_split(row_ptr, nbr, cb):
    """Per chunk, the first row with a partner beyond the chunk (rows before it need no check)."""
    C = cb.shape[0] - 1
    split = cb[1:].copy()
    for c in range(C):
        for i in range(cb[c], cb[c + 1]):
            hit = False
            for k in range(row_ptr[i], row_ptr[i + 1]):
                if nbr[k] >= cb[c + 1]:
                    hit = True
                    break
            if hit:
                split[c] = i
                break
    return split


class PairWorkspace:
    """Chunk layout and scratch buffers for the pair loops over one pair list.

    Build it once per pair list and pass it to every kernel call (the kernels make a temporary
    one when none is given).

    Parameters
    ----------
    row_ptr, nbr
        The CSR pair list (int64 (N+1,), int32 (P,)); every pair must have i < nbr[k] < N.
    n_chunks
        Number of chunks C; default ``numba.get_num_threads()``, or 1 for fewer than
        ``SERIAL_BELOW_PAIRS`` pairs. With C = 1 the kernels run their serial build. Results are
        bit-identical run to run for the same C.

    Attributes
    ----------
    chunk_ptr
        int64 (C+1,) first row of each chunk (chunks hold equal numbers of pairs).
    split
        int64 (C,) first row of each chunk with a partner beyond the chunk; the hot loops check
        for overflow only from there on.
    ov_ptr
        int64 (C+1,) offsets of each chunk's overflow rows in ``ov``; chunk c's overflow covers
        particles ``chunk_ptr[c+1] : chunk_ptr[c+1] + ov_ptr[c+1] - ov_ptr[c]``.
    ov
        float64 (ov_ptr[-1], 3) overflow buffer.
    coef
        float64 (N, 2) per-particle force coefficients (theta (3K - 5mu) / m, 15 mu / m).
    bond_length
        float64 (P,) current bond lengths kept by :func:`dilatation_and_forces` (None until
        that is first called).
    """

    def __init__(self, row_ptr: np.ndarray, nbr: np.ndarray, n_chunks: int | None = None):
        row_ptr = np.asarray(row_ptr)
        nbr = np.asarray(nbr)
        n = row_ptr.shape[0] - 1
        if n < 0 or row_ptr[0] != 0 or row_ptr[-1] != nbr.shape[0]:
            raise ValueError("row_ptr must start at 0 and end at the number of pairs len(nbr)")
        if not _pairs_forward(row_ptr, nbr):
            raise ValueError(
                "the pair list must hold unique pairs i < j grouped by i (nbr[k] > i for k in "
                "row i, and every index below N)"
            )
        P = nbr.shape[0]
        if n_chunks is None:
            C = 1 if P < SERIAL_BELOW_PAIRS else int(numba.get_num_threads())
        else:
            C = int(n_chunks)
        C = max(1, min(C, max(n, 1)))
        targets = (np.arange(C + 1, dtype=np.int64) * P) // C
        cb = np.searchsorted(row_ptr, targets, side="left").astype(np.int64)
        cb[0] = 0
        cb[-1] = n
        cb = np.maximum.accumulate(cb)
        ov_len = np.zeros(C, dtype=np.int64)
        for c in range(C):
            k0, k1 = row_ptr[cb[c]], row_ptr[cb[c + 1]]
            if k1 > k0:
                ov_len[c] = max(0, int(nbr[k0:k1].max()) + 1 - int(cb[c + 1]))
        self.n = n
        self.n_pairs = P
        self.n_chunks = C
        self.chunk_ptr = cb
        self.split = _chunk_split(row_ptr, nbr, cb)
        self.ov_ptr = np.concatenate(([0], np.cumsum(ov_len))).astype(np.int64)
        self.ov = np.zeros((int(self.ov_ptr[-1]), 3))
        self.coef = np.empty((n, 2))
        self.counts = np.zeros(C, dtype=np.int64)
        self.parallel = C > 1
        self.bond_length: np.ndarray | None = None

    def bond_length_buffer(self) -> np.ndarray:
        """The (P,) float64 scratch of :func:`dilatation_and_forces` (allocated on first use)."""
        if self.bond_length is None:
            self.bond_length = np.empty(self.n_pairs)
        return self.bond_length

    def check(self, row_ptr: np.ndarray, nbr: np.ndarray) -> None:
        """Raise ValueError if this workspace was not built for a list of this size."""
        if row_ptr.shape[0] - 1 != self.n or nbr.shape[0] != self.n_pairs:
            raise ValueError(
                f"workspace built for {self.n} particles and {self.n_pairs} pairs, got "
                f"{row_ptr.shape[0] - 1} and {nbr.shape[0]}"
            )


def _c(a: np.ndarray, name: str) -> np.ndarray:
    """``a`` itself if C-contiguous (the kernels index flat views), else ValueError."""
    if not a.flags.c_contiguous:
        raise ValueError(f"{name} must be a C-contiguous array")
    return a


def _ws(ws, row_ptr, nbr):
    if ws is None:
        return PairWorkspace(row_ptr, nbr)
    ws.check(row_ptr, nbr)
    return ws


# --------------------------------------------------------------------------- pair loops
#
# Index arithmetic is unsigned (``_U``) inside the pair loops: numba then emits no
# negative-index wraparound code for the gathers and scatters, which is a large part of the
# instruction count of these short loop bodies.


@_twin()
def _family_sum_pairs(row_ptr, nbr, xi_len, vol, hi, inv_dx, mode, cb, ov_ptr, ov, out):
    """out_i = sum_j g(|xi|) beta vol_j over all bonds, g = |xi|^2, 1/|xi|, |xi|, 1 (mode 0..3)."""
    C = cb.shape[0] - 1
    for c in prange(C):
        r0 = cb[c]
        r1 = _U(cb[c + 1])
        base = _U(ov_ptr[c])
        for p in range(r0, r1):
            out[p] = 0.0
        for q in range(base, _U(ov_ptr[c + 1])):
            ov[q, 0] = 0.0
        for i in range(r0, r1):
            vi = vol[i]
            acc = 0.0
            for k in range(_U(row_ptr[i]), _U(row_ptr[i + 1])):
                j = _U(nbr[k])
                l = xi_len[k]
                if mode == 0:
                    g = l * l
                elif mode == 1:
                    g = 1.0 / l
                elif mode == 2:
                    g = l
                else:
                    g = 1.0
                g *= _beta(l, hi, inv_dx)
                acc += g * vol[j]
                if j < r1:
                    out[j] += g * vi
                else:
                    ov[base + (j - r1), 0] += g * vi
            out[i] += acc
    for t in prange(C):
        _add_overflow1(t, cb, ov_ptr, ov, 0, out)


@numba.njit(cache=True, inline="always", fastmath=_FM, error_model="numpy")
def _dilatation_row(i, y, row_ptr, nbr, xi_len, broken, vol, hi, inv_dx, theta, checked, r1, ov,
                    base, rbuf, store_r):
    """Row i of the pair-loop dilatation (``checked``: partners may lie beyond row r1)."""
    yi0 = y[3 * i]
    yi1 = y[3 * i + 1]
    yi2 = y[3 * i + 2]
    vi = vol[i]
    acc = 0.0
    for k in range(_U(row_ptr[i]), _U(row_ptr[i + 1])):
        if broken[k] != 0:
            continue
        j = _U(nbr[k])
        j3 = _U(3) * j
        l = xi_len[k]
        d0 = y[j3] - yi0
        d1 = y[j3 + _U(1)] - yi1
        d2 = y[j3 + _U(2)] - yi2
        r = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        if store_r:
            rbuf[k] = r
        g = _beta(l, hi, inv_dx) * l * (r - l)
        acc += g * vol[j]
        if checked and j >= r1:
            ov[base + (j - r1), 0] += g * vi
        else:
            theta[j] += g * vi
    theta[i] += acc


@_twin()
def _dilatation_pairs(y2, row_ptr, nbr, xi_len, broken, vol, m, hi, inv_dx, cb, split, ov_ptr, ov,
                      theta, rbuf, store_r):
    """Pair-loop dilatation; with ``store_r`` also rbuf[k] = |y_j - y_i| of unbroken bonds."""
    y = y2.reshape(y2.size)  # flat view: 3 j + c indexing, no stride multiplications
    C = cb.shape[0] - 1
    for c in prange(C):
        r0 = cb[c]
        r1 = _U(cb[c + 1])
        base = _U(ov_ptr[c])
        for p in range(r0, r1):
            theta[p] = 0.0
        for q in range(base, _U(ov_ptr[c + 1])):
            ov[q, 0] = 0.0
        for i in range(r0, split[c]):
            _dilatation_row(i, y, row_ptr, nbr, xi_len, broken, vol, hi, inv_dx, theta, False, r1,
                            ov, base, rbuf, store_r)
        for i in range(split[c], r1):
            _dilatation_row(i, y, row_ptr, nbr, xi_len, broken, vol, hi, inv_dx, theta, True, r1,
                            ov, base, rbuf, store_r)
    for t in prange(C):
        _add_overflow1(t, cb, ov_ptr, ov, 0, theta)
        for p in range(cb[t], cb[t + 1]):
            theta[p] = 3.0 * theta[p] / m[p] if m[p] > 0.0 else 0.0


@_twin(fastmath=False)
def _coefficients(m, theta, K, mu, coef):
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


@numba.njit(cache=True, inline="always", fastmath=_FM, error_model="numpy")
def _forces_row(i, y, row_ptr, nbr, xi_len, broken, vol, coef, hi, inv_dx, s0, nofail, f, checked,
                r1, ov, base, rbuf, use_r):
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
    for k in range(_U(row_ptr[i]), _U(row_ptr[i + 1])):
        if broken[k] != 0:
            continue
        j = _U(nbr[k])
        j3 = _U(3) * j
        l = xi_len[k]
        d0 = y[j3] - yi0
        d1 = y[j3 + _U(1)] - yi1
        d2 = y[j3 + _U(2)] - yi2
        if use_r:
            r = rbuf[k]
        else:
            r = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        e = r - l
        if e > s0 * l and can_i and nofail[j] == 0:
            broken[k] = 1
            nb += 1
            continue
        j2 = _U(2) * j
        g = ((ai + coef[j2]) * l + (bi + coef[j2 + _U(1)]) * e) * _beta(l, hi, inv_dx) / r
        gi = g * vol[j]
        fx += gi * d0
        fy += gi * d1
        fz += gi * d2
        gj = g * vi
        if checked and j >= r1:
            q = _U(3) * (base + (j - r1))
            ov[q] -= gj * d0
            ov[q + _U(1)] -= gj * d1
            ov[q + _U(2)] -= gj * d2
        else:
            f[j3] -= gj * d0
            f[j3 + _U(1)] -= gj * d1
            f[j3 + _U(2)] -= gj * d2
    f[3 * i] += fx
    f[3 * i + 1] += fy
    f[3 * i + 2] += fz
    return nb


@_twin()
def _forces_pairs(y2, row_ptr, nbr, xi_len, broken, vol, coef2, hi, inv_dx, s0, nofail,
                  cb, split, ov_ptr, ov2, counts, fout, rbuf, use_r):
    """Pair-loop force density and breaking; with ``use_r`` the bond lengths come from rbuf."""
    y = y2.reshape(y2.size)  # flat views: 3 j + c indexing, no stride multiplications
    coef = coef2.reshape(coef2.size)
    f = fout.reshape(fout.size)
    ov = ov2.reshape(ov2.size)
    C = cb.shape[0] - 1
    for c in prange(C):
        r0 = cb[c]
        r1 = _U(cb[c + 1])
        base = _U(ov_ptr[c])
        for p in range(3 * r0, 3 * r1):
            f[p] = 0.0
        for q in range(_U(3) * base, _U(3) * _U(ov_ptr[c + 1])):
            ov[q] = 0.0
        nb = 0
        for i in range(r0, split[c]):
            nb += _forces_row(i, y, row_ptr, nbr, xi_len, broken, vol, coef, hi, inv_dx, s0,
                              nofail, f, False, r1, ov, base, rbuf, use_r)
        for i in range(split[c], r1):
            nb += _forces_row(i, y, row_ptr, nbr, xi_len, broken, vol, coef, hi, inv_dx, s0,
                              nofail, f, True, r1, ov, base, rbuf, use_r)
        counts[c] = nb
    for t in prange(C):
        _add_overflow3(t, cb, ov_ptr, ov2, fout)
    total = 0
    for c in range(C):
        total += counts[c]
    return total


@_twin()
def _energy_pairs(y, row_ptr, nbr, xi_len, broken, vol, m, theta, K, mu, hi, inv_dx,
                  cb, ov_ptr, ov, W):
    C = cb.shape[0] - 1
    for c in prange(C):
        r0 = cb[c]
        r1 = _U(cb[c + 1])
        base = _U(ov_ptr[c])
        for p in range(r0, r1):
            W[p] = 0.0
        for q in range(base, _U(ov_ptr[c + 1])):
            ov[q, 0] = 0.0
        for i in range(r0, r1):
            ti = theta[i] / 3.0
            vi = vol[i]
            acc = 0.0
            for k in range(_U(row_ptr[i]), _U(row_ptr[i + 1])):
                if broken[k] != 0:
                    continue
                j = _U(nbr[k])
                l = xi_len[k]
                d0 = y[j, 0] - y[i, 0]
                d1 = y[j, 1] - y[i, 1]
                d2 = y[j, 2] - y[i, 2]
                e = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2) - l
                b = _beta(l, hi, inv_dx)
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
        _add_overflow1(t, cb, ov_ptr, ov, 0, W)
        for p in range(cb[t], cb[t + 1]):
            s = 7.5 * mu * W[p] / m[p] if m[p] > 0.0 else 0.0
            W[p] = 0.5 * K * theta[p] * theta[p] + s


@_twin(fastmath=False)
def _damage_pairs(row_ptr, nbr, broken, cb, ov_ptr, ov, nb, deg):
    C = cb.shape[0] - 1
    for c in prange(C):
        r0 = cb[c]
        r1 = _U(cb[c + 1])
        base = _U(ov_ptr[c])
        for p in range(r0, r1):
            nb[p] = 0.0
            deg[p] = 0.0
        for q in range(base, _U(ov_ptr[c + 1])):
            ov[q, 0] = 0.0
            ov[q, 1] = 0.0
        for i in range(r0, r1):
            cnt = 0.0
            for k in range(_U(row_ptr[i]), _U(row_ptr[i + 1])):
                j = _U(nbr[k])
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
        _add_overflow1(t, cb, ov_ptr, ov, 0, nb)
        _add_overflow1(t, cb, ov_ptr, ov, 1, deg)
        for p in range(cb[t], cb[t + 1]):
            nb[p] = nb[p] / deg[p] if deg[p] > 0.0 else 0.0


# --------------------------------------------------------------------------- full family


@numba.njit(parallel=True, cache=True, fastmath=_FM, error_model="numpy")
def _dilatation_family(y2, fam_ptr, fam_nbr, fam_bond, xi_len, broken, vol, m, hi, inv_dx, theta):
    y = y2.reshape(y2.size)
    for i in prange(fam_ptr.shape[0] - 1):
        yi0 = y[3 * i]
        yi1 = y[3 * i + 1]
        yi2 = y[3 * i + 2]
        acc = 0.0
        for q in range(_U(fam_ptr[i]), _U(fam_ptr[i + 1])):
            k = _U(fam_bond[q])
            if broken[k] != 0:
                continue
            j = _U(fam_nbr[q])
            j3 = _U(3) * j
            l = xi_len[k]
            d0 = y[j3] - yi0
            d1 = y[j3 + _U(1)] - yi1
            d2 = y[j3 + _U(2)] - yi2
            r = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            acc += _beta(l, hi, inv_dx) * l * (r - l) * vol[j]
        theta[i] = 3.0 * acc / m[i] if m[i] > 0.0 else 0.0


@numba.njit(parallel=True, cache=True, fastmath=_FM, error_model="numpy")
def _forces_family(y2, fam_ptr, fam_nbr, fam_bond, xi_len, broken, vol, coef2, hi, inv_dx, s0,
                   nofail, fout):
    y = y2.reshape(y2.size)
    coef = coef2.reshape(coef2.size)
    f = fout.reshape(fout.size)
    nb = 0
    for i in prange(fam_ptr.shape[0] - 1):
        yi0 = y[3 * i]
        yi1 = y[3 * i + 1]
        yi2 = y[3 * i + 2]
        ai = coef[2 * i]
        bi = coef[2 * i + 1]
        can_i = nofail[i] == 0
        iu = _U(i)
        fx = 0.0
        fy = 0.0
        fz = 0.0
        for q in range(_U(fam_ptr[i]), _U(fam_ptr[i + 1])):
            k = _U(fam_bond[q])
            if broken[k] != 0:
                continue
            j = _U(fam_nbr[q])
            j3 = _U(3) * j
            l = xi_len[k]
            d0 = y[j3] - yi0
            d1 = y[j3 + _U(1)] - yi1
            d2 = y[j3 + _U(2)] - yi2
            r = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
            e = r - l
            if e > s0 * l and can_i and nofail[j] == 0:
                # Both ends reach the same decision from the same stretch; only the smaller
                # index marks and counts the bond, so the count is exact. (The larger end may
                # read the flag before or after that write: it skips the bond either way.)
                if iu < j:
                    broken[k] = 1
                    nb += 1
                continue
            j2 = _U(2) * j
            g = ((ai + coef[j2]) * l + (bi + coef[j2 + _U(1)]) * e) * _beta(l, hi, inv_dx) / r
            g *= vol[j]
            fx += g * d0
            fy += g * d1
            fz += g * d2
        f[3 * i] = fx
        f[3 * i + 1] = fy
        f[3 * i + 2] = fz
    return nb


# --------------------------------------------------------------------------- public API


def weighted_volume(
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    vol: np.ndarray,
    delta: float,
    dx: float,
    ws: PairWorkspace | None = None,
) -> np.ndarray:
    """Weighted volume m_i = sum_j |xi|^2 beta V_j over all initial bonds.

    Parameters
    ----------
    row_ptr, nbr
        CSR unique pairs i < j (int64 (N+1,), int32 (P,)).
    xi_len
        (P,) reference bond lengths (m).
    vol
        (N,) particle volumes (m^3).
    delta, dx
        Horizon and lattice spacing (m).
    ws
        Optional :class:`PairWorkspace` for this pair list.

    Returns
    -------
    ndarray
        (N,) float64 weighted volume (m^5).
    """
    ws = _ws(ws, row_ptr, nbr)
    return _family_sum(row_ptr, nbr, xi_len, vol, delta, dx, 0, ws)


def dilatation(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    delta: float,
    dx: float,
    theta_out: np.ndarray,
    ws: PairWorkspace | None = None,
) -> None:
    """Dilatation theta_i = (3 / m_i) sum_j |xi| e beta V_j over unbroken bonds (pair loop).

    Parameters
    ----------
    y
        (N, 3) current positions (m).
    row_ptr, nbr, xi_len, broken
        Pair list, reference lengths (m) and broken flags (uint8).
    vol, m
        (N,) volumes (m^3) and weighted volumes (m^5, :func:`weighted_volume`).
    delta, dx
        Horizon and lattice spacing (m).
    theta_out
        (N,) float64, overwritten with the dilatation (dimensionless); 0 where m = 0.
    ws
        Optional :class:`PairWorkspace` for this pair list.
    """
    ws = _ws(ws, row_ptr, nbr)
    _dilatation_pairs(ws.parallel, _c(y, "y"), row_ptr, nbr, xi_len, broken, vol, m,
                      delta + 0.5 * dx, 1.0 / dx, ws.chunk_ptr, ws.split, ws.ov_ptr, ws.ov,
                      theta_out, _NO_R, False)


def forces(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    theta: np.ndarray,
    K: float,
    mu: float,
    delta: float,
    dx: float,
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
    row_ptr, nbr, xi_len
        Pair list and reference bond lengths (m).
    broken
        (P,) uint8, updated in place.
    vol, m, theta
        (N,) volumes (m^3), weighted volumes (m^5) and dilatations of this step.
    K, mu
        Bulk and shear modulus (Pa).
    delta, dx
        Horizon and lattice spacing (m).
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
    ws = _ws(ws, row_ptr, nbr)
    _coefficients(ws.parallel, m, theta, K, mu, ws.coef)
    return int(_forces_pairs(ws.parallel, _c(y, "y"), row_ptr, nbr, xi_len, broken, vol, ws.coef,
                             delta + 0.5 * dx, 1.0 / dx, float(s0), nofail, ws.chunk_ptr,
                             ws.split, ws.ov_ptr, ws.ov, ws.counts, _c(f_out, "f_out"), _NO_R,
                             False))


def dilatation_and_forces(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    K: float,
    mu: float,
    delta: float,
    dx: float,
    s0: float,
    nofail: np.ndarray,
    theta_out: np.ndarray,
    f_out: np.ndarray,
    ws: PairWorkspace,
) -> int:
    """One OSB step's internal forces: :func:`dilatation`, then :func:`forces` (pair loops).

    Bit-identical to the two calls, but faster: the dilatation pass stores every unbroken
    bond's current length in the workspace (``ws.bond_length``, float64 (P,), allocated on first
    use: 8 bytes per pair) and the force pass reads it instead of taking a second square root.

    Parameters are those of :func:`dilatation` and :func:`forces`; ``theta_out`` (N,) and
    ``f_out`` (N, 3) are overwritten; ``ws`` is required.

    Returns
    -------
    int
        Number of bonds broken in this call.
    """
    ws.check(row_ptr, nbr)
    rbuf = ws.bond_length_buffer()
    hi, inv_dx = delta + 0.5 * dx, 1.0 / dx
    _dilatation_pairs(ws.parallel, _c(y, "y"), row_ptr, nbr, xi_len, broken, vol, m, hi, inv_dx,
                      ws.chunk_ptr, ws.split, ws.ov_ptr, ws.ov, theta_out, rbuf, True)
    _coefficients(ws.parallel, m, theta_out, K, mu, ws.coef)
    return int(_forces_pairs(ws.parallel, y, row_ptr, nbr, xi_len, broken, vol, ws.coef, hi,
                             inv_dx, float(s0), nofail, ws.chunk_ptr, ws.split, ws.ov_ptr,
                             ws.ov, ws.counts, _c(f_out, "f_out"), rbuf, True))


def strain_energy(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    theta: np.ndarray,
    K: float,
    mu: float,
    delta: float,
    dx: float,
    ws: PairWorkspace | None = None,
) -> np.ndarray:
    """Strain energy density W_i = K theta_i^2 / 2 + (15 mu / (2 m_i)) sum_j e_d^2 beta V_j.

    Parameters are as in :func:`forces` (``theta`` from :func:`dilatation` for the same ``y``).

    Returns
    -------
    ndarray
        (N,) float64 energy density (J/m^3); the total strain energy is ``(W * vol).sum()``.
    """
    ws = _ws(ws, row_ptr, nbr)
    W = np.empty(ws.n)
    _energy_pairs(ws.parallel, y, row_ptr, nbr, xi_len, broken, vol, m, theta, float(K), float(mu),
                  delta + 0.5 * dx, 1.0 / dx, ws.chunk_ptr, ws.ov_ptr, ws.ov, W)
    return W


def damage(
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    broken: np.ndarray,
    n: int,
    ws: PairWorkspace | None = None,
) -> np.ndarray:
    """Damage: the broken fraction of each particle's initial bonds (0 for a particle without).

    Parameters
    ----------
    row_ptr, nbr, broken
        Pair list and broken flags; every pair counts for both its ends.
    n
        Number of particles N.
    ws
        Optional :class:`PairWorkspace` for this pair list.

    Returns
    -------
    ndarray
        (N,) float64 in [0, 1].
    """
    if row_ptr.shape[0] != n + 1:
        raise ValueError(f"row_ptr must have n + 1 = {n + 1} entries, got {row_ptr.shape[0]}")
    ws = _ws(ws, row_ptr, nbr)
    out = np.empty(n)
    deg = np.empty(n)
    _damage_pairs(ws.parallel, row_ptr, nbr, broken, ws.chunk_ptr, ws.ov_ptr, ws.ov, out, deg)
    return out


def dilatation_family(
    y: np.ndarray,
    fam_ptr: np.ndarray,
    fam_nbr: np.ndarray,
    fam_bond: np.ndarray,
    xi_len: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    delta: float,
    dx: float,
    theta_out: np.ndarray,
) -> None:
    """Dilatation by the per-particle full-family loop (reference for :func:`dilatation`).

    ``fam_ptr``, ``fam_nbr``, ``fam_bond`` come from :func:`pdfem.pd.family.build_family`; the
    other parameters are as in :func:`dilatation`.
    """
    _dilatation_family(_c(y, "y"), fam_ptr, fam_nbr, fam_bond, xi_len, broken, vol, m,
                       delta + 0.5 * dx, 1.0 / dx, theta_out)


def forces_family(
    y: np.ndarray,
    fam_ptr: np.ndarray,
    fam_nbr: np.ndarray,
    fam_bond: np.ndarray,
    xi_len: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    theta: np.ndarray,
    K: float,
    mu: float,
    delta: float,
    dx: float,
    s0: float,
    nofail: np.ndarray,
    f_out: np.ndarray,
    coef: np.ndarray | None = None,
) -> int:
    """Force density by the per-particle full-family loop (reference for :func:`forces`).

    Every bond is evaluated from both ends; each particle writes only its own force. A bond
    breaking in this call is marked by its smaller-index end (both ends reach the same decision
    from the same stretch, so the larger end needs no write and the count is exact).

    Parameters
    ----------
    fam_ptr, fam_nbr, fam_bond
        Family lists from :func:`pdfem.pd.family.build_family`.
    coef
        Optional (N, 2) float64 scratch for the per-particle coefficients.
    others
        As in :func:`forces`.

    Returns
    -------
    int
        Number of bonds broken in this call.
    """
    n = fam_ptr.shape[0] - 1
    if coef is None:
        coef = np.empty((n, 2))
    _coefficients(True, m, theta, K, mu, coef)
    return int(_forces_family(_c(y, "y"), fam_ptr, fam_nbr, fam_bond, xi_len, broken, vol,
                              _c(coef, "coef"), delta + 0.5 * dx, 1.0 / dx, float(s0), nofail,
                              _c(f_out, "f_out")))


# --------------------------------------------------------------------------- integration


@_twin(fastmath=False)
def _kick(v, f, inv_rho, half_dt, g, free):
    uniform = inv_rho.shape[0] == 1
    all_free = free.shape[0] == 0
    for i in prange(v.shape[0]):
        if all_free or free[i] != 0:
            ir = inv_rho[0] if uniform else inv_rho[i]
            v[i, 0] += half_dt * (f[i, 0] * ir + g[0])
            v[i, 1] += half_dt * (f[i, 1] * ir + g[1])
            v[i, 2] += half_dt * (f[i, 2] * ir + g[2])


@_twin(fastmath=False)
def _drift(y, v, dt):
    for i in prange(y.shape[0]):
        y[i, 0] += dt * v[i, 0]
        y[i, 1] += dt * v[i, 1]
        y[i, 2] += dt * v[i, 2]


def verlet_kick(
    v: np.ndarray,
    f: np.ndarray,
    inv_rho: float | np.ndarray,
    half_dt: float,
    gravity: np.ndarray | tuple[float, float, float] = (0.0, 0.0, 0.0),
    free_mask: np.ndarray | None = None,
) -> None:
    """Velocity half step of velocity Verlet, in place: ``v += half_dt * (f / rho + g)``.

    Parameters
    ----------
    v
        (N, 3) velocities (m/s), updated in place.
    f
        (N, 3) force density (N/m^3).
    inv_rho
        1 / density (m^3/kg), a scalar or (N,) array.
    half_dt
        The velocity increment's time step, normally dt / 2 (s).
    gravity
        (3,) body acceleration (m/s^2).
    free_mask
        Optional (N,) uint8/bool: particles with 0 keep their velocity (prescribed motion).
    """
    ir = np.atleast_1d(np.asarray(inv_rho, dtype=np.float64))
    g = np.asarray(gravity, dtype=np.float64).reshape(3)
    if free_mask is None:
        free = np.zeros(0, dtype=np.uint8)
    else:
        free = np.ascontiguousarray(free_mask).view(np.uint8)
    _kick(v.shape[0] >= SERIAL_BELOW_PARTICLES, v, f, ir, float(half_dt), g, free)


def verlet_drift(y: np.ndarray, v: np.ndarray, dt: float) -> None:
    """Position update of velocity Verlet, in place: ``y += dt * v`` (m, m/s, s)."""
    _drift(y.shape[0] >= SERIAL_BELOW_PARTICLES, y, v, float(dt))


# --------------------------------------------------------------------------- time step


def _family_sum(row_ptr, nbr, xi_len, w, delta, dx, mode, ws):
    out = np.empty(ws.n)
    _family_sum_pairs(ws.parallel, row_ptr, nbr, xi_len, w, delta + 0.5 * dx, 1.0 / dx, mode,
                      ws.chunk_ptr, ws.ov_ptr, ws.ov, out)
    return out


def stable_time_step(
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    vol: np.ndarray,
    delta: float,
    dx: float,
    density: float,
    K: float,
    mu: float | None = None,
    ws: PairWorkspace | None = None,
) -> float:
    """Stable explicit (velocity Verlet) time step (s).

    Without ``mu``: the estimate of Silling & Askari (2005),
    ``min_i sqrt(2 rho / sum_j beta V_j c / |xi|)`` with the bond-based micromodulus
    ``c = 18 K / (pi delta^4)``. It is the Gershgorin bound of the bond-based model, not of the
    LPS. Checked against the largest eigenvalue of the linearised LPS system
    (:func:`max_eigenvalue_time_step`), delta = 3.015 dx: on lattice blocks of 6^3 to 24^3 the
    true critical step is 1.13-1.15 (nu = 0), 1.77-1.85 (nu = 0.3) and 2.17-2.21 (nu = 0.45)
    times this estimate (1.01 at nu = 0, delta = 2.015 dx), so it is safe for bulky bodies
    without any scaling. It is NOT safe for bodies only one or two particles thick (the LPS
    normalises every family by its weighted volume, so thin bodies keep bulk-like stiffness
    while the bond-based sum drops): for a 16 x 16 x 1 sheet the true step is 0.47 (nu = 0) to
    0.97 (nu = 0.45) of the estimate, for a chain of particles 0.16-0.36.

    With ``mu`` (recommended): the Gershgorin bound of the linearised LPS itself, which is
    below the true critical step for every body shape and 0 <= nu < 0.5: with
    ``k_ij = 15 mu (1/m_i + 1/m_j)`` (the shear part of W; the bulk part is
    ``(K - 5 mu/3) theta^2 / 2`` and only counts when positive, nu > 1/4)::

        lambda_i = (2/rho) sum_j k_ij beta V_j
                   + (max(K - 5 mu/3, 0)/rho) (2 A_i^2 + sum_j (6/m_j) |xi| beta V_j A_j),
        A_i = (3/m_i) sum_j |xi| beta V_j,       dt = 2 / sqrt(max_i lambda_i).

    Measured (delta = 3.015 dx): 0.48-0.50 (nu = 0), 0.48-0.49 (nu = 0.3) and 0.40-0.41
    (nu = 0.45) of the true step on blocks of 6^3 to 24^3, 0.46-0.79 on sheets and rods.

    Parameters
    ----------
    row_ptr, nbr, xi_len, vol
        Pair list (all initial bonds), bond lengths (m), volumes (m^3).
    delta, dx
        Horizon and lattice spacing (m).
    density
        Mass density (kg/m^3).
    K
        Bulk modulus (Pa).
    mu
        Shear modulus (Pa); selects the LPS bound.
    ws
        Optional :class:`PairWorkspace`.

    Returns
    -------
    float
        The time step (s); ``inf`` when there are no bonds.
    """
    ws = _ws(ws, row_ptr, nbr)
    if ws.n == 0 or ws.n_pairs == 0:
        return math.inf
    if mu is None:
        s = _family_sum(row_ptr, nbr, xi_len, vol, delta, dx, 1, ws)
        c = 18.0 * K / (math.pi * delta**4)
        return math.sqrt(2.0 * density / (c * float(s.max())))
    m = _family_sum(row_ptr, nbr, xi_len, vol, delta, dx, 0, ws)
    inv_m = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0.0)
    sum_v = _family_sum(row_ptr, nbr, xi_len, vol, delta, dx, 3, ws)
    sum_vm = _family_sum(row_ptr, nbr, xi_len, vol * inv_m, delta, dx, 3, ws)
    lam = (30.0 * mu / density) * (inv_m * sum_v + sum_vm)
    kb = K - 5.0 * mu / 3.0
    if kb > 0.0:
        A = 3.0 * inv_m * _family_sum(row_ptr, nbr, xi_len, vol, delta, dx, 2, ws)
        S = _family_sum(row_ptr, nbr, xi_len, 6.0 * vol * inv_m * A, delta, dx, 2, ws)
        lam += (kb / density) * (2.0 * A * A + S)
    lmax = float(lam.max())
    return 2.0 / math.sqrt(lmax) if lmax > 0.0 else math.inf


def max_eigenvalue_time_step(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    K: float,
    mu: float,
    delta: float,
    dx: float,
    density: float,
    rel_step: float = 1e-6,
    tol: float = 1e-6,
    ws: PairWorkspace | None = None,
) -> float:
    """True critical step ``2 / sqrt(lambda_max)`` of the LPS system linearised at ``y`` (s).

    ``lambda_max`` is the largest eigenvalue of ``M^-1 Kt`` (``M = rho V``, ``Kt`` the tangent
    stiffness ``-d(V L)/dy``), found by Lanczos iteration (ARPACK ``eigsh``, the Krylov
    refinement of power iteration) on the symmetric form ``M^-1/2 Kt M^-1/2``. Each product is a
    central finite difference of two force evaluations (dilatation + forces, no breaking) with
    displacements of ``rel_step * dx``; expect some tens to a few hundred force evaluations, so
    it is cheap for small bodies and a check (not a per-run step) for large ones. No particle is
    held fixed, which can only raise ``lambda_max`` (a safe side).

    Parameters
    ----------
    y
        (N, 3) positions about which to linearise (m), usually the reference positions.
    row_ptr, nbr, xi_len, broken, vol, m
        As in :func:`forces` (``broken`` is read, never changed).
    K, mu
        Bulk and shear modulus (Pa).
    delta, dx
        Horizon and lattice spacing (m).
    density
        Mass density (kg/m^3).
    rel_step
        Finite-difference displacement relative to dx.
    tol
        Relative tolerance of the eigenvalue.
    ws
        Optional :class:`PairWorkspace`.

    Returns
    -------
    float
        The critical time step of velocity Verlet / central differences (s).
    """
    from scipy.sparse.linalg import LinearOperator, eigsh

    ws = _ws(ws, row_ptr, nbr)
    n = ws.n
    h = rel_step * dx
    sq = np.sqrt(vol / density)  # sqrt(V / rho)
    inv_sqm = 1.0 / np.sqrt(density * vol)  # 1 / sqrt(rho V)
    nofail = np.ones(n, dtype=np.uint8)
    theta = np.empty(n)
    fp = np.empty((n, 3))
    fm = np.empty((n, 3))
    yp = np.empty((n, 3))

    def force_at(u, out):
        np.add(y, u, out=yp)
        dilatation(yp, row_ptr, nbr, xi_len, broken, vol, m, delta, dx, theta, ws)
        forces(yp, row_ptr, nbr, xi_len, broken, vol, m, theta, K, mu, delta, dx, math.inf,
               nofail, out, ws)

    def matvec(x):
        u = (x.reshape(n, 3) * inv_sqm[:, None]) * h
        force_at(u, fp)
        force_at(-u, fm)
        return (-(fp - fm) / (2.0 * h) * sq[:, None]).ravel()

    op = LinearOperator((3 * n, 3 * n), matvec=matvec, dtype=np.float64)
    v0 = np.random.default_rng(0).standard_normal(3 * n)
    lam = float(eigsh(op, k=1, which="LA", tol=tol, v0=v0, return_eigenvectors=False)[0])
    return 2.0 / math.sqrt(lam) if lam > 0.0 else math.inf
