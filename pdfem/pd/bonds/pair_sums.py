"""The pair loops' sums outside the time step: strain energy, the potential of crushed bonds,
damage (public API over :mod:`pdfem.pd.bonds.pair_sum_kernels`; data layout in
:mod:`pdfem.pd.bonds.pair_loop`). SI units: J/m^3, J.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pdfem.pd.bonds.data import Bonds
from pdfem.pd.bonds.pair_loop import (bond_tuple, check_broken, check_weight, particle_tuple,
                                      rest_arg)
from pdfem.pd.bonds.pair_sum_kernels import contact_bond_energy_pairs, damage_pairs, energy_pairs
from pdfem.pd.bonds.workspace import workspace_for

_NO_SLIP = np.zeros(0, dtype=np.float32)  # "no shear springs" (read-only by convention)
_NO_THETA = np.zeros(0)  # "no dilatation needed" (read-only by convention)
_NO_LENGTHS = np.zeros(0)  # "no bond lengths needed" (read-only by convention)

if TYPE_CHECKING:
    from pdfem.pd.bonds.workspace import PairWorkspace


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
    lengths: np.ndarray | None = None,
) -> np.ndarray:
    """Strain energy density W_i = K theta_i^2 / 2 + (15 mu / (2 m_i)) sum_j omega e_d^2 V_j.

    Parameters are as in :func:`forces` (``theta`` from :func:`dilatation` for the same ``y``);
    ``lengths`` (P,), if given, holds every unbroken bond's current length |y_j - y_i| (m), as
    the fused step keeps it (``ws.bond_length``): read instead of taken again, the same bits.

    Returns
    -------
    ndarray
        (N,) float64 energy density (J/m^3); the total strain energy is ``(W * vol).sum()``.
    """
    ws = workspace_for(ws, row_ptr, nbr)
    W = np.empty(ws.n)
    energy_pairs(ws.parallel, bond_tuple(row_ptr, nbr, xi_len, weight, broken),
                 particle_tuple(y, vol, m, theta), float(K), float(mu), ws.blocks, W,
                 _NO_LENGTHS if lengths is None else lengths, lengths is not None)
    return W


def contact_bond_energy(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    broken: np.ndarray,
    rest: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    mu: float,
    owned: np.ndarray | None = None,
    slip: np.ndarray | None = None,
    kappa: float = 0.0,
) -> float:
    """Energy (J) stored in the crushed bonds (``rest`` of :func:`pdfem.pd.bonds.pair_loop.forces`):
    sum of (b_i + b_j) |omega| V_i V_j (r_p - r)^2 / 2 over those shorter than their plastic
    rest length r_p = |xi| (1 + rest), b = 15 mu / m; only the bonds i < j with ``owned[i]``
    if ``owned`` ((N,) bool) is given. With ``slip`` ((P, 3), m) and ``kappa``, plus the energy
    of their shear springs (:mod:`pdfem.pd.failure.crushed_shear`)."""
    rest, _ = rest_arg(rest, nbr)
    mask = np.zeros(0, dtype=np.bool_) if owned is None else np.asarray(owned, dtype=np.bool_)
    return float(contact_bond_energy_pairs(bond_tuple(row_ptr, nbr, xi_len, weight, broken),
                                           particle_tuple(y, vol, m, _NO_THETA), rest, float(mu),
                                           mask, _NO_SLIP if slip is None else slip.reshape(-1),
                                           float(kappa)))


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
    damage_pairs(ws.parallel, Bonds(row_ptr, nbr, _NO_LENGTHS, weight, broken), ws.blocks, out,
                 deg)
    return out


