"""The weighted volume of each particle's intact bonds, which keeps the LPS forces of a damaged
body the exact gradient of its strain energy.

The LPS strain energy (:mod:`pdfem.pd.lps_law`) normalises by the weighted volume m of all
initial bonds, W_i = K theta_i^2 / 2 + (15 mu / (2 m_i)) sum_j omega e_d^2 V_j over the intact
bonds. Its exact derivative with respect to a bond's extension is the usual force state plus a
term in c_i = sum_j omega e_d l V_j over the intact bonds, which vanishes on an intact family
but not once bonds are broken: c_i = theta_i (m_i - m'_i) / 3 with m'_i the weighted volume of
the intact bonds. The force state's a-coefficient is then

    a_i = theta_i (3 K - 5 mu (2 - m'_i / m_i)) / m_i

(:func:`pdfem.pd.lps_law.force_coefficients`), and velocity Verlet conserves the energy of a
breaking body to O(dt^2) between breaks; without it every break put about half a bond's energy
into the motion (a block crushed to pieces gained 16 % of its energy).

:func:`intact_weighted_volume` computes m' = m - (the broken bonds' omega |xi|^2 V_j), summed
for each particle over its broken bonds in the order of the partners' global numbers, so a
body split over MPI ranks gets the same bits as the whole body; a particle without a broken
bond keeps m' = m exactly. SI units: m^5.
"""

from __future__ import annotations

import numpy as np


def intact_weighted_volume(row_ptr: np.ndarray, nbr: np.ndarray, xi_len: np.ndarray,
                           weight: np.ndarray, broken: np.ndarray, vol: np.ndarray,
                           m: np.ndarray, gid: np.ndarray | None = None) -> np.ndarray:
    """m'_i = m_i - sum over particle i's broken bonds of |omega| |xi|^2 V_j (m^5).

    Parameters
    ----------
    row_ptr, nbr, xi_len, weight
        The pair list (i < j grouped by i), reference lengths (m) and bond weights.
    broken
        (P,) bool: which bonds are broken.
    vol, m
        (N,) volumes (m^3) and weighted volumes of all initial bonds (m^5).
    gid
        (N,) global particle numbers (default: the local ones), which fix the summation order.
    """
    n = m.shape[0]
    k = np.flatnonzero(broken)
    if len(k) == 0:
        return m.copy()
    gid = np.arange(n) if gid is None else np.asarray(gid)
    i = np.searchsorted(row_ptr, k, side="right") - 1
    j = nbr[k].astype(np.int64)
    g = xi_len[k] * xi_len[k] * np.abs(weight[k]).astype(np.float64)
    owner = np.concatenate([i, j])
    partner = np.concatenate([j, i])
    value = np.concatenate([g * vol[j], g * vol[i]])
    order = np.lexsort((gid[partner], owner))
    lost = np.bincount(owner[order], weights=value[order], minlength=n)
    out = m - lost
    keep = np.bincount(owner, minlength=n) == 0
    out[keep] = m[keep]
    return out
