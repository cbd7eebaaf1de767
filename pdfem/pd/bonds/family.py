"""Full (both-direction) family lists built from the unique bond pairs.

The kernels' main data structure is the list of unique pairs i < j grouped by i (CSR:
``row_ptr``, ``nbr``; the "particle-pair method" of Zhang et al. 2023). The original PD
algorithm instead loops, for every particle, over its whole family, so every bond is visited
twice. :func:`build_family` turns the pair list into that per-particle family list; it is kept
as the reference for tests and for the pair-loop benchmark (see
:func:`pdfem.pd.bonds.kernels.forces_family`).
"""

from __future__ import annotations

import numba
import numpy as np

from pdfem.pd.bonds.family_kernels import (dilatation_family_loop, forces_family_loop,
                                           mark_family_breaks)
from pdfem.pd.bonds.lps_law import force_coefficients, stretch_limits
from pdfem.pd.bonds.pair_loop import INTACT, UNIT_STRENGTH, check_broken, check_weight
from pdfem.pd.bonds.workspace import c_contiguous


@numba.njit(cache=True)
def _build_family(row_ptr, nbr, n):
    deg = np.zeros(n, dtype=np.int64)
    for i in range(n):
        deg[i] += row_ptr[i + 1] - row_ptr[i]
        for k in range(row_ptr[i], row_ptr[i + 1]):
            deg[nbr[k]] += 1
    fam_ptr = np.zeros(n + 1, dtype=np.int64)
    for i in range(n):
        fam_ptr[i + 1] = fam_ptr[i] + deg[i]
    fam_nbr = np.empty(fam_ptr[n], dtype=np.int32)
    fam_bond = np.empty(fam_ptr[n], dtype=np.int64)
    fill = fam_ptr[:n].copy()
    # Rows are visited in increasing i; when row i is reached all bonds coming from i' < i are
    # already in place, so each family lists its smaller neighbours first (ascending), then its
    # own row (ascending when nbr is ascending within rows).
    for i in range(n):
        for k in range(row_ptr[i], row_ptr[i + 1]):
            j = nbr[k]
            q = fill[i]
            fam_nbr[q] = j
            fam_bond[q] = k
            fill[i] = q + 1
            q = fill[j]
            fam_nbr[q] = i
            fam_bond[q] = k
            fill[j] = q + 1
    return fam_ptr, fam_nbr, fam_bond


def build_family(
    row_ptr: np.ndarray, nbr: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both-direction family lists of the unique pairs.

    Parameters
    ----------
    row_ptr
        int64 (N+1,) CSR offsets of the unique pairs (i < j) grouped by i.
    nbr
        int32 (P,) partner j of pair k.
    n
        Number of particles N.

    Returns
    -------
    fam_ptr
        int64 (N+1,): the family of particle i is entries ``fam_ptr[i]:fam_ptr[i+1]``.
    fam_nbr
        int32 (2P,): family member (the other particle of the bond).
    fam_bond
        int64 (2P,): index of the unique pair, so both directions share ``xi_len[k]`` and
        ``broken[k]``.

    Each family lists the smaller neighbours first (ascending), then the larger ones in row
    order.
    """
    row_ptr = np.ascontiguousarray(row_ptr, dtype=np.int64)
    nbr = np.ascontiguousarray(nbr, dtype=np.int32)
    if row_ptr.shape != (n + 1,):
        raise ValueError(f"row_ptr must have n + 1 = {n + 1} entries, got {row_ptr.shape}")
    if nbr.size and (nbr.min() < 0 or nbr.max() >= n):
        raise ValueError("nbr holds particle indices outside 0..n-1")
    return _build_family(row_ptr, nbr, n)


def dilatation_family(
    y: np.ndarray,
    fam_ptr: np.ndarray,
    fam_nbr: np.ndarray,
    fam_bond: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    theta_out: np.ndarray,
) -> None:
    """Dilatation by the per-particle full-family loop (reference for the pair loop).

    ``fam_ptr``, ``fam_nbr``, ``fam_bond`` come from :func:`pdfem.pd.bonds.family.build_family`; the
    other parameters are as in :func:`pdfem.pd.bonds.pair_loop.dilatation`.
    """
    dilatation_family_loop(c_contiguous(y, "y"), fam_ptr, fam_nbr, fam_bond, xi_len, broken,
                       check_broken(broken, xi_len), vol, m, check_weight(weight, xi_len), theta_out)


def forces_family(
    y: np.ndarray,
    fam_ptr: np.ndarray,
    fam_nbr: np.ndarray,
    fam_bond: np.ndarray,
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
    coef: np.ndarray | None = None,
    m_now: np.ndarray | None = None,
) -> int:
    """Force density by the per-particle full-family loop (reference for the pair loop).

    Every bond is evaluated from both ends; each particle writes only its own force. A bond
    that breaks at these positions still acts in this evaluation (as in the pair loop: the
    step's force is that of the bonds intact at its start, so the time integration stays
    energy-consistent and the energy the bond held is the fracture's) and is marked afterwards,
    once, by its smaller-index end.

    Parameters
    ----------
    fam_ptr, fam_nbr, fam_bond
        Family lists from :func:`pdfem.pd.bonds.family.build_family`.
    coef
        Optional (N, 2) float64 scratch for the per-particle force coefficients.
    m_now
        Optional weighted volume of the intact bonds, as in
        :func:`pdfem.pd.bonds.pair_loop.forces`.
    others
        As in :func:`pdfem.pd.bonds.pair_loop.forces`.

    Returns
    -------
    int
        Number of bonds broken in this call.
    """
    n = fam_ptr.shape[0] - 1
    if coef is None:
        coef = np.empty((n, 2))
    if coef.shape != (n, 2):
        raise ValueError(f"coef must be an (N, 2) float64 scratch array, got shape {coef.shape}")
    aux = np.empty((n, 2))
    force_coefficients(True, m, INTACT if m_now is None else m_now, theta, K, mu, UNIT_STRENGTH,
                       coef, aux)
    yc, signed, wt = c_contiguous(y, "y"), check_broken(broken, xi_len), check_weight(weight, xi_len)
    forces_family_loop(yc, fam_ptr, fam_nbr, fam_bond, xi_len, broken, signed, vol,
                   c_contiguous(coef, "coef"), wt, c_contiguous(f_out, "f_out"))
    return int(mark_family_breaks(yc, fam_ptr, fam_nbr, fam_bond, xi_len, broken, signed, wt, aux,
                            nofail, stretch_limits(s0)))


