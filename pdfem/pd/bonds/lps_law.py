"""The LPS force law, written once: per-bond physics as small inlined numba helpers.

The linear peridynamic solid (Silling et al. 2007; DESIGN.md "Peridynamics") per bond
(i, j) with reference length l = |xi|, current length r = |y_j - y_i| and extension e = r - l::

    dilatation:     theta_i = (3 / m_i) sum_j omega l e V_j
    force state:    t_ij = (3 K theta_i / m_i) l + (15 mu / m_i) e_d,   e_d = e - theta_i l / 3
                         = a_i l + b_i e,   a_i = theta_i (3K - 5mu) / m_i,   b_i = 15 mu / m_i
    pair force:     (t_ij + t_ji) omega (y_j - y_i) / r
    breaking:       e / l > s_max or e / l < s_min, unless an end has ``nofail``; the bounds
                    depend on the bond's mean dilatation theta = (theta_i + theta_j) / 2:
                    s_max = t0 + t1 theta, s_min = min(c0 + c1 theta, d0 + d1 theta) (the
                    failure law's :meth:`~pdfem.pd.failure.base.FailureLaw.stretch_limits`;
                    the critical stretch is (s0, 0, -inf, 0, -inf, 0))

Every kernel that evaluates the law (the pair loops of :mod:`pdfem.pd.bonds.pair_step_kernels` and
:mod:`pdfem.pd.bonds.pair_sum_kernels`, the full-family reference loops of
:mod:`pdfem.pd.bonds.family_kernels`, and through the pair loops the MPI ranks of
:mod:`pdfem.pd.layout.halo`) calls these helpers. They are ``inline="always"``: numba pastes
their IR into the caller, which compiles them with its own flags, so a helper costs nothing and
the floating-point operations (and their order) are exactly those of the formulas above.
:func:`force_coefficients` is the per-particle half of the force state (a_i, b_i) and, apart,
half the particle's dilatation and strength factor (so that a bond's mean is the sum of its
ends', one gather each).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import prange

from pdfem.parallel.kernels import fma, twin
from pdfem.pd.bonds.chunk_kernels import U64

_INLINE = dict(cache=True, inline="always")


@numba.njit(**_INLINE)
def bond_vector(y, j3, yi0, yi1, yi2):
    """Current bond vector y_j - y_i from the flat positions ``y`` (j3 = 3 j) and y_i."""
    return y[j3] - yi0, y[j3 + U64(1)] - yi1, y[j3 + U64(2)] - yi2


@numba.njit(**_INLINE)
def bond_length(d0, d1, d2):
    """Current bond length r = |d| (m)."""
    return math.sqrt(fma(d2, d2, fma(d1, d1, d0 * d0)))


@numba.njit(**_INLINE)
def is_broken(signed, w, broken, k):
    """Whether bond k is broken: its weight ``w`` is negative (``signed``) or its flag is set."""
    if signed:
        return w < 0.0
    return broken[k] != 0


@numba.njit(**_INLINE)
def mark_broken(signed, wt, w, broken, k):
    """Mark bond k broken for good: negate its weight (``signed``) or set its flag."""
    if signed:
        wt[k] = -w
    else:
        broken[k] = 1


@numba.njit(**_INLINE)
def dilatation_term(w, l, r):
    """A bond's dilatation summand omega l e (to be weighted by the partner's volume)."""
    return w * l * (r - l)


@numba.njit(**_INLINE)
def dilatation_of(s, m):
    """theta = 3 s / m from the family sum s of :func:`dilatation_term` times V_j (0 if m = 0)."""
    return 3.0 * s / m if m > 0.0 else 0.0


@numba.njit(**_INLINE)
def breaks(e, l, th, fs, lim, can_i, nofail, j):
    """The failure test: stretch e / l outside the bounds ``lim`` = (t0, t1, c0, c1, d0, d1)
    at the bond's mean dilatation ``th`` (module doc), the compressive strength scaled by the
    ends' mean strength factor ``fs`` (1 without a rate dependence), and neither end ``nofail``."""
    if not (can_i and nofail[j] == 0):
        return False
    if e > (lim[0] + lim[1] * th) * l:
        return True
    return e < min(lim[2] * fs + lim[3] * th, lim[4] * fs + lim[5] * th) * l


@numba.njit(**_INLINE)
def breaks_stretch(e, l, s0, can_i, nofail, j):
    """The critical-stretch test alone: stretch e / l above s0 and neither end ``nofail``
    (what :func:`breaks` reduces to for bounds ``(s0, 0, -inf, 0, -inf, 0)``)."""
    return e > s0 * l and can_i and nofail[j] == 0


def stretch_limits(s0) -> np.ndarray:
    """The six stretch-bound coefficients (t0, t1, c0, c1, d0, d1) the kernels take (module doc).

    ``s0`` is either a critical stretch (a scalar: ``(s0, 0, -inf, 0, -inf, 0)``) or the six
    coefficients of a failure law's :meth:`~pdfem.pd.failure.base.FailureLaw.stretch_limits`.
    """
    a = np.asarray(s0, dtype=np.float64).reshape(-1)
    if a.shape[0] == 1:
        return np.array([a[0], 0.0, -math.inf, 0.0, -math.inf, 0.0])
    if a.shape[0] != 6:
        raise ValueError(f"stretch limits are a critical stretch or 6 numbers, got {a.shape[0]}")
    return a


@numba.njit(**_INLINE)
def pair_force_scalar(a, b, l, e, w, r):
    """(t_ij + t_ji) omega / r, with a = a_i + a_j and b = b_i + b_j (see the module doc):
    times V_j (y_j - y_i) it is the force density on i, times V_i (y_i - y_j) that on j."""
    return fma(a, l, b * e) * w / r


@numba.njit(**_INLINE)
def crushed_bond(b, l, p, sy, w, r, vij):
    """A broken bond that still pushes (crushed ice, :mod:`pdfem.pd.failure.ice`): a
    compression-only, elastic-perfectly-plastic spring between its ends.

    With b = b_i + b_j, weight magnitude ``w`` and its plastic rest length r_p = l (1 + p), it
    pushes with k (r_p - r), k = b w V_i V_j, while r < r_p, up to a compression of ``sy`` l
    (the yield stretch); beyond it r_p slides to r + sy l and the spring's force k sy l does
    work that is dissipated. Returns the force scalar g (times V_j (y_j - y_i): the force
    density on i, as :func:`pair_force_scalar`), the new p and the energy dissipated (J;
    ``vij`` = V_i V_j)."""
    rp = l * (1.0 + p)
    c = rp - r
    if c <= 0.0:
        return 0.0, p, 0.0
    cap = sy * l
    diss = 0.0
    if c > cap:
        p = (r + cap - l) / l
        diss = b * w * cap * c - b * w * cap * cap  # F_cap (r_p - r_p,new)
        diss *= vij
        c = cap
    return -b * w * c / r, p, diss


@numba.njit(**_INLINE)
def crushed_shear(s0, s1, s2, u0, u1, u2, d0, d1, d2, r, smax):
    """Shear of a pushing crushed bond: the tangential spring with Coulomb slip between its
    ends (crushed ice is a frictional granular material; Cundall & Strack 1979).

    ``s`` (m) is the spring's stretch: the sliding of j past i since the bond was crushed,
    normal to the bond, less what has slipped. Each step it is turned into the plane normal to
    the current bond d (its length kept), the tangential part of the bond vector's increment
    ``u`` = d - d_old (m) is added, and it is capped at ``smax`` = mu c / kappa (the Coulomb
    limit |k_t s| <= mu k c of a bond compressed by c, tangential stiffness k_t = kappa k);
    the excess slips. Returns the new s and the energy lost by slipping per k_t (m^2): the
    step's work on the spring, k_t (s_old + s_new) / 2 . u as the integrator's trapezoid does
    it, less the change of its energy k_t |s|^2 / 2, which the caller books as dissipated."""
    n0 = d0 / r
    n1 = d1 / r
    n2 = d2 / r
    old2 = s0 * s0 + s1 * s1 + s2 * s2
    sn = s0 * n0 + s1 * n1 + s2 * n2
    p0 = s0 - sn * n0
    p1 = s1 - sn * n1
    p2 = s2 - sn * n2
    pl2 = p0 * p0 + p1 * p1 + p2 * p2
    if pl2 > 0.0:  # turned with the bond, its length kept
        scale = math.sqrt(old2 / pl2)
        p0 *= scale
        p1 *= scale
        p2 *= scale
    else:
        p0 = 0.0
        p1 = 0.0
        p2 = 0.0
    un = u0 * n0 + u1 * n1 + u2 * n2
    t0 = p0 + u0 - un * n0
    t1 = p1 + u1 - un * n1
    t2 = p2 + u2 - un * n2
    new2 = t0 * t0 + t1 * t1 + t2 * t2
    lost = 0.0 if pl2 > 0.0 else 0.5 * old2  # along the bond: nothing to turn, released
    if new2 > smax * smax:
        keep = smax / math.sqrt(new2)
        # the step's work (trapezoid, k_t (s_old + s_new) / 2 . u, as the integrator does it)
        # less the spring's energy change: (s_old + s_new) / 2 . (s_trial - s_new)
        lost += 0.5 * (1.0 - keep) * (p0 * t0 + p1 * t1 + p2 * t2 + keep * new2)
        t0 *= keep
        t1 *= keep
        t2 *= keep
    return t0, t1, t2, lost


@numba.njit(**_INLINE)
def crushed_bond_energy(b, l, p, w, r):
    """The stored energy of :func:`crushed_bond` per V_i V_j: b w (r_p - r)^2 / 2 (0 if r >= r_p)."""
    c = l * (1.0 + p) - r
    if c > 0.0:
        return 0.5 * b * w * c * c
    return 0.0


@numba.njit(**_INLINE)
def crushed_rest(e, l, sy):
    """p of a bond breaking at extension ``e``: its plastic rest length is min(l, r + sy l),
    so it pushes at once with at most the yield force (no drop of the force it carried)."""
    return min(0.0, e / l + sy)


@numba.njit(**_INLINE)
def deviatoric_extension(e, theta_third, l):
    """e_d = e - theta l / 3, with ``theta_third`` = theta / 3 of the particle concerned."""
    return e - theta_third * l


@numba.njit(**_INLINE)
def energy_density(K, mu, theta, s, m):
    """W = K theta^2 / 2 + (15 mu / (2 m)) s, with s = sum_j omega e_d^2 V_j (J/m^3)."""
    d = 7.5 * mu * s / m if m > 0.0 else 0.0
    return 0.5 * K * theta * theta + d


@twin(fastmath=False)
def force_coefficients(m, m_now, theta, K, mu, strength, coef, aux):
    """coef[:, 0] = a = theta (3K - 5mu (2 - m'/m)) / m, coef[:, 1] = b = 15 mu / m (0 where
    m = 0), with m' = ``m_now`` the weighted volume of the intact bonds (empty: m' = m; the
    a of a damaged particle that keeps the force the energy's gradient,
    :mod:`pdfem.pd.failure.damaged_volume`); aux[:, 0] = theta / 2 (a bond's mean dilatation is the
    sum over its ends) and aux[:, 1] = strength / 2, the particle's compressive-strength factor
    (1 if ``strength`` is empty) halved likewise. Two arrays, so that a plain critical stretch
    gathers only ``coef`` (16 bytes per partner)."""
    unit = strength.shape[0] == 0
    intact = m_now.shape[0] == 0
    c1 = 3.0 * K - 5.0 * mu
    c2 = 15.0 * mu
    for p in prange(m.shape[0]):
        th = theta[p]
        if m[p] > 0.0:
            im = 1.0 / m[p]
            if intact or m_now[p] == m[p]:
                coef[p, 0] = th * c1 * im
            else:
                coef[p, 0] = th * (3.0 * K - 5.0 * mu * (2.0 - m_now[p] * im)) * im
            coef[p, 1] = c2 * im
        else:
            coef[p, 0] = 0.0
            coef[p, 1] = 0.0
        aux[p, 0] = 0.5 * th
        aux[p, 1] = 0.5 if unit else 0.5 * strength[p]
