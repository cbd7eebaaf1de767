"""The weighted volume of each particle's intact bonds, which keeps the LPS forces of a damaged
body the exact gradient of its strain energy.

The LPS strain energy (:mod:`pdfem.pd.bonds.lps_law`) normalises by the weighted volume m of all
initial bonds, W_i = K theta_i^2 / 2 + (15 mu / (2 m_i)) sum_j omega e_d^2 V_j over the intact
bonds. Its exact derivative with respect to a bond's extension is the usual force state plus a
term in c_i = sum_j omega e_d l V_j over the intact bonds, which vanishes on an intact family
but not once bonds are broken: c_i = theta_i (m_i - m'_i) / 3 with m'_i the weighted volume of
the intact bonds. The force state's a-coefficient is then

    a_i = theta_i (3 K - 5 mu (2 - m'_i / m_i)) / m_i

(:func:`pdfem.pd.bonds.lps_law.force_coefficients`), and velocity Verlet conserves the energy of a
breaking body to O(dt^2) between breaks; without it every break put about half a bond's energy
into the motion (a block crushed to pieces gained 16 % of its energy).

:class:`IntactVolume` keeps m' = m - (the broken bonds' |omega| |xi|^2 V_j), summed for each
particle over its broken bonds in the order of the partners' global numbers, so a body split
over MPI ranks gets the same bits as the whole body; a particle without a broken bond keeps
m' = m exactly. After a step that broke bonds only the particles those bonds touch are summed
again (one pass over the broken flags to find them, one bit per bond remembered). SI: m^5.
"""

from __future__ import annotations

import numpy as np


class IntactVolume:
    """m' of one body (or one rank's part of it), updated as its bonds break.

    Parameters
    ----------
    m
        (N,) weighted volumes of all initial bonds (m^5).
    gid
        (N,) global particle numbers (default: the local ones), which fix the summation order.
    """

    def __init__(self, m: np.ndarray, gid: np.ndarray | None = None) -> None:
        self.m = m
        self.gid = np.arange(m.shape[0]) if gid is None else np.asarray(gid)
        self.now: np.ndarray | None = None   # (N,) m'; None before the first update
        self._seen: np.ndarray | None = None  # packed bits: the broken bonds already summed

    def update(self, row_ptr: np.ndarray, nbr: np.ndarray, xi_len: np.ndarray,
               weight: np.ndarray, broken: np.ndarray, vol: np.ndarray) -> np.ndarray | None:
        """m' after bonds broke (``broken``: (P,) bool)."""
        if self.now is None:
            self.now = self.m.copy()
        seen = (np.zeros(len(broken), dtype=bool) if self._seen is None
                else np.unpackbits(self._seen, count=len(broken)).astype(bool))
        new = np.flatnonzero(broken & ~seen)
        self._seen = np.packbits(broken)
        if len(new) == 0:
            return self.now
        n = self.m.shape[0]
        touched = np.zeros(n, dtype=bool)
        touched[np.searchsorted(row_ptr, new, side="right") - 1] = True
        touched[nbr[new]] = True
        k = np.flatnonzero(broken)
        i = np.searchsorted(row_ptr, k, side="right") - 1
        j = nbr[k].astype(np.int64)
        sel = touched[i] | touched[j]
        k, i, j = k[sel], i[sel], j[sel]
        g = xi_len[k] * xi_len[k] * np.abs(weight[k]).astype(np.float64)
        owner = np.concatenate([i, j])
        partner = np.concatenate([j, i])
        value = np.concatenate([g * vol[j], g * vol[i]])
        keep = touched[owner]
        owner, partner, value = owner[keep], partner[keep], value[keep]
        order = np.lexsort((self.gid[partner], owner))
        lost = np.bincount(owner[order], weights=value[order], minlength=n)
        self.now[touched] = self.m[touched] - lost[touched]
        return self.now

    def forget(self) -> None:
        """Sum every particle again at the next :meth:`update` (the flags were set anew)."""
        self.now = None
        self._seen = None
