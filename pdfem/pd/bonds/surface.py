"""Surface correction of the LPS bond weights: isotropic second moments in truncated families.

Why (design note)
-----------------
Under a uniform strain eps the LPS dilatation of particle i is (linearised, n = xi / |xi|)::

    theta_i = (3 / m_i) sum_j omega |xi|^2 (n.eps.n) V_j = (3 / m_i) M2_i : eps,
    M2_i = sum_j omega |xi|^2 n n V_j,   m_i = tr M2_i,

so theta_i = tr(eps) for every strain iff ``M2_i = (m_i / 3) I``. A complete family on a cubic
lattice has that by symmetry, but a family cut by a free surface lacks the bonds pointing out
of the body, and its M2 is anisotropic. Measured on a 14 x 14 bar (delta = 3.015 dx, nu = 0.3,
uniaxial stress): in the two outer particle layers theta is 31 % and 37 % too large and the
energy density 23 % and 19 % too large, so the bar is 12 % too stiff (E = 1.12 E_input from
the core strains under end tractions), a surface effect that no affordable block size removes.

What
----
Each bond gets a factor ``c_k = clip(1 + n.(C_i + C_j).n / 2, 1/2, 2)`` (symmetric in its two
ends, so the bond keeps one weight and the pair loops are unchanged), with a symmetric 3 x 3
tensor C_i per particle chosen so that every family's M2, computed with the corrected weights
``omega_k c_k``, is isotropic. The tensors come from the fixed-point iteration::

    D_i = 3 M2_i / m_i - I,      C_i <- C_i - (5/2) D_i

(for a nearly isotropic fourth moment a change C of the weights changes M2 by (2 m / 15) C, so
the step cancels D_i to first order). Bulk families away from surfaces have D ~ 0 and c ~ 1. Along
edges and at corners no positive weight can make M2 isotropic (the off-diagonal moment of a
quarter or octant family is positive for any positive weight); the clip keeps every weight
within a factor 2 of the uncorrected one there. With the correction the outer layers of the bar
have theta = tr(eps) (to 1e-3 in the 14 x 14 bar) and energy densities within 6 %; E and nu
come out within 2 %.
The idea is that of the position-aware LPS (Mitchell, Silling & Littlewood 2015, "A
position-aware linear solid constitutive model for peridynamics", J. Mech. Mater. Struct. 10),
which makes the moments isotropic with per-particle influence functions; here the correction
is symmetrised so that it fits the one-weight-per-bond storage and costs nothing per step.
The setup cost is a pass over the pairs per iteration (``iterations + 1`` passes), threaded
with the blocked, deterministic pair loop of :mod:`pdfem.pd.bonds.workspace` (on a rank's part
of a body with the halo's tensors exchanged after every pass), under the float flags
``FASTMATH`` of :mod:`pdfem.parallel.kernels` (no FMA contraction: freshly compiled and cached
code give the same bits).
"""

from __future__ import annotations

import numba
import numpy as np

from pdfem.parallel.kernels import FASTMATH
from pdfem.pd.bonds.data import Bonds
from pdfem.pd.bonds.workspace import PairWorkspace


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _add_moments(M, p, g, aa, bb, cc, ab, ac, bc):
    M[p, 0] += g * aa
    M[p, 1] += g * bb
    M[p, 2] += g * cc
    M[p, 3] += g * ab
    M[p, 4] += g * ac
    M[p, 5] += g * bc


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _bond_weight(x, i, j, C, ln, w0, lo, hi):
    """The corrected weight of bond (i, j) from the tensors C (reference length ``ln``, weight
    ``w0``, factor clipped to [lo, hi]) and the bond's second-moment products."""
    a = x[j, 0] - x[i, 0]
    b = x[j, 1] - x[i, 1]
    cz = x[j, 2] - x[i, 2]
    aa = a * a
    bb = b * b
    cc = cz * cz
    ab = a * b
    ac = a * cz
    bc = b * cz
    q = ((C[i, 0] + C[j, 0]) * aa + (C[i, 1] + C[j, 1]) * bb
         + (C[i, 2] + C[j, 2]) * cc + (C[i, 3] + C[j, 3]) * ab
         + (C[i, 4] + C[j, 4]) * ac + (C[i, 5] + C[j, 5]) * bc)
    f = min(hi, max(lo, 1.0 + 0.5 * q / (ln * ln)))
    return w0 * f, aa, bb, cc, ab, ac, bc


@numba.njit(cache=True, fastmath=FASTMATH, inline="always")
def _update_tensor(C, M, i):
    """One fixed-point update of particle i's tensor C from its moments M."""
    m = M[i, 0] + M[i, 1] + M[i, 2]
    if m > 0.0:
        s7 = 7.5 / m  # (5/2) * 3 / m
        C[i, 0] -= s7 * M[i, 0] - 2.5
        C[i, 1] -= s7 * M[i, 1] - 2.5
        C[i, 2] -= s7 * M[i, 2] - 2.5
        C[i, 3] -= 2.0 * s7 * M[i, 3]
        C[i, 4] -= 2.0 * s7 * M[i, 4]
        C[i, 5] -= 2.0 * s7 * M[i, 5]


@numba.njit(cache=True, parallel=True, fastmath=FASTMATH)
def corrected_pass(x, bonds, vol, clip, blocks, C, M, ov, last, out):
    """One pass of the fixed-point iteration as a race-free pair loop over the blocks
    (:mod:`pdfem.pd.bonds.workspace`): block c sums the moments of its rows, the j side of bonds
    leaving the block into its own overflow rows, which are added in block order; then every
    row's tensor C is updated from its moments. With ``last``, the corrected weights go to
    ``out`` instead (``out`` may be the weights: each is read for the last time there).
    ``clip`` = (lo, hi) bounds of the factor, ``blocks`` the :class:`~pdfem.pd.bonds.data.
    Blocks`; the tensors ``C``, moments ``M`` and overflow rows ``ov`` are written, so they
    come as arrays of their own (numba loses writes through tuples in a ``prange``)."""
    row_ptr, nbr, xi_len, w0 = bonds.row_ptr, bonds.nbr, bonds.xi_len, bonds.weight
    lo, hi = clip
    cb, ov_ptr = blocks.ptr, blocks.ov_ptr
    nc = cb.shape[0] - 1
    for c in numba.prange(nc):
        r0 = cb[c]
        r1 = cb[c + 1]
        base = ov_ptr[c]
        M[r0:r1] = 0.0
        ov[base:ov_ptr[c + 1]] = 0.0
        for i in range(r0, r1):
            for k in range(row_ptr[i], row_ptr[i + 1]):
                j = nbr[k]
                g, aa, bb, cc, ab, ac, bc = _bond_weight(x, i, j, C, xi_len[k], w0[k], lo, hi)
                if last:
                    out[k] = g
                    continue
                _add_moments(M, i, g * vol[j], aa, bb, cc, ab, ac, bc)
                if j < r1:
                    _add_moments(M, j, g * vol[i], aa, bb, cc, ab, ac, bc)
                else:
                    _add_moments(ov, base + j - r1, g * vol[i], aa, bb, cc, ab, ac, bc)
    if last:
        return
    for t in numba.prange(nc):
        r0 = cb[t]
        r1 = cb[t + 1]
        for c in range(t):
            s = cb[c + 1]
            e = s + (ov_ptr[c + 1] - ov_ptr[c])
            for p in range(max(s, r0), min(e, r1)):
                for col in range(6):
                    M[p, col] += ov[ov_ptr[c] + p - s, col]
        for i in range(r0, r1):
            _update_tensor(C, M, i)


def surface_corrected_weights(
    x: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    vol: np.ndarray,
    iterations: int = 20,
    bounds: tuple[float, float] = (0.5, 2.0),
    ws: PairWorkspace | None = None,
    out: np.ndarray | None = None,
    exchange=None,
) -> np.ndarray:
    """Bond weights with the surface correction: every family's second moment made isotropic.

    Parameters
    ----------
    x
        (N, 3) reference positions (m).
    row_ptr, nbr
        CSR unique pairs i < j (int64 (N+1,), int32 (P,)).
    xi_len
        (P,) reference bond lengths (m).
    weight
        (P,) uncorrected bond weights omega (:func:`pdfem.pd.bonds.influence.bond_weights`).
    vol
        (N,) particle volumes (m^3).
    iterations
        Fixed-point iterations (20 bring the second moments of faces to 3e-3 of isotropy).
    bounds
        Smallest and largest correction factor of a bond.
    ws
        Optional :class:`~pdfem.pd.bonds.workspace.PairWorkspace` of the pair list: its blocks
        (fixed by the whole body) thread the loop and fix the order of every sum.
    out
        Optional (P,) float32 array for the result; it may be ``weight`` itself (corrected in
        place, which saves 4 bytes per pair of set-up memory).
    exchange
        For a rank's part of a body: overwrites the halo rows of a per-particle array with
        their owners' values; called on the tensors C after every iteration, so each owned
        particle sees exactly the C the whole body's iteration gives it (its halo partners'
        families are incomplete here).

    Returns
    -------
    ndarray
        (P,) float32 corrected bond weights.
    """
    if out is None:
        out = np.empty(np.asarray(nbr).shape[0], dtype=np.float32)
    elif (out.dtype != np.float32 or out.shape != np.asarray(nbr).shape
          or not out.flags.c_contiguous):
        raise ValueError("out must be a C-contiguous float32 array with one entry per pair")
    ws = PairWorkspace(row_ptr, nbr) if ws is None else ws
    ws.check(row_ptr, nbr)
    n = row_ptr.shape[0] - 1
    C = np.zeros((n, 6))  # xx, yy, zz, 2 xy, 2 xz, 2 yz
    M = np.empty((n, 6))  # sum omega d d V (d = x_j - x_i): xx, yy, zz, xy, xz, yz
    ov = np.empty((ws.ov_ptr[-1], 6))
    x = np.ascontiguousarray(x, dtype=np.float64)
    w0 = np.ascontiguousarray(weight, dtype=np.float32)
    vol = np.asarray(vol, dtype=np.float64)
    for it in range(iterations + 1):
        last = it == iterations
        corrected_pass(x, Bonds(row_ptr, nbr, xi_len, w0), vol,
                       (float(bounds[0]), float(bounds[1])), ws.blocks, C, M, ov, last, out)
        if not last and exchange is not None:
            exchange(C)
    return out
