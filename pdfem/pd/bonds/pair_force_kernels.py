"""One bond's force applied to both of its ends, and the shear spring of a crushed bond
(:mod:`pdfem.pd.failure.crushed_shear`): inlined helpers of the pair-loop force kernels
(:mod:`pdfem.pd.bonds.pair_step_kernels`). Units: SI."""

from __future__ import annotations

import numba

from pdfem.parallel.kernels import FASTMATH, fma
from pdfem.pd.bonds.chunk_kernels import U64
from pdfem.pd.bonds.lps_law import crushed_shear


@numba.njit(cache=True, inline="always", fastmath=FASTMATH, error_model="numpy")
def apply_pair_force(g, vj, vi, d0, d1, d2, fx, fy, fz, j, j3, checked, r1, ov, base, f):
    """A bond's force scalar ``g`` applied to both ends: the row's sums (fx, fy, fz) get
    g V_j d (returned), partner j gets -g V_i d, in ``f`` or, past row r1 with ``checked``, in
    the chunk's overflow rows."""
    gi = g * vj
    fx = fma(gi, d0, fx)
    fy = fma(gi, d1, fy)
    fz = fma(gi, d2, fz)
    gj = -g * vi
    if checked and j >= r1:
        q = U64(3) * (base + (j - r1))
        ov[q] = fma(gj, d0, ov[q])
        ov[q + U64(1)] = fma(gj, d1, ov[q + U64(1)])
        ov[q + U64(2)] = fma(gj, d2, ov[q + U64(2)])
    else:
        f[j3] = fma(gj, d0, f[j3])
        f[j3 + U64(1)] = fma(gj, d1, f[j3 + U64(1)])
        f[j3 + U64(2)] = fma(gj, d2, f[j3 + U64(2)])
    return fx, fy, fz


@numba.njit(cache=True, inline="always", fastmath=FASTMATH, error_model="numpy")
def apply_crushed_shear(k, i, j, j3, y, y0, slip, shear, g, b, w, r, d0, d1, d2, vi, vj, fx, fy, fz,
                   checked, r1, ov, base, f):
    """The shear spring of crushed bond k (:func:`~pdfem.pd.bonds.lps_law.crushed_shear`):
    ``shear`` = (mu, kappa, advance). With ``advance`` its stretch ``slip[3k:3k+3]`` (m) takes
    the step's increment of the bond vector (from the positions ``y0`` at the step's start);
    then its force kappa b w V_i V_j s acts on both ends. Returns the row's sums and the energy
    (J) it dissipated by slipping."""
    k3 = U64(3) * k
    s0 = (1.0 * slip[k3])
    s1 = (1.0 * slip[k3 + U64(1)])
    s2 = (1.0 * slip[k3 + U64(2)])
    kb = shear[1] * b * w
    lost = 0.0
    if shear[2] != 0.0:
        i3 = U64(3) * U64(i)
        u0 = d0 - (y0[j3] - y0[i3])
        u1 = d1 - (y0[j3 + U64(1)] - y0[i3 + U64(1)])
        u2 = d2 - (y0[j3 + U64(2)] - y0[i3 + U64(2)])
        smax = shear[0] * (-g * r / (b * w)) / shear[1] if g < 0.0 else 0.0
        s0, s1, s2, lost = crushed_shear(s0, s1, s2, u0, u1, u2, d0, d1, d2, r, smax)
        slip[k3] = s0
        slip[k3 + U64(1)] = s1
        slip[k3 + U64(2)] = s2
        s0 = (1.0 * slip[k3])
        s1 = (1.0 * slip[k3 + U64(1)])
        s2 = (1.0 * slip[k3 + U64(2)])
    if s0 != 0.0 or s1 != 0.0 or s2 != 0.0:
        fx, fy, fz = apply_pair_force(kb, vj, vi, s0, s1, s2, fx, fy, fz, j, j3, checked, r1, ov,
                                 base, f)
    return fx, fy, fz, lost * kb * vi * vj
