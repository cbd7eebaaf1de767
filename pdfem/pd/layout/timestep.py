"""The stable time step of an ice body split over ranks, equal to the serial body's.

:func:`pdfem.pd.timestep.stable_time_step` (the Gershgorin bound of the linearised LPS) sums,
for each particle, over its family terms that hold the neighbours' weighted volumes m_j and
family sums A_j. On a rank an owned particle has its whole family, but its halo neighbours do
not, so their m_j and A_j are taken from their owners (``exchange``) before the sums that use
them; the per-particle bound is then the serial one for every owned particle, and the step is
the smallest over the owned particles of all ranks. Units: s, SI inputs.
"""

from __future__ import annotations

import math

import numpy as np

from pdfem.pd.bonds.pair_loop import family_sum


def split_stable_time_step(body, owned: np.ndarray, exchange, comm) -> float:
    """The serial :meth:`IceBody.stable_time_step <pdfem.pd.body.IceBody.stable_time_step>` of
    the whole body from one rank's part ``body`` (collective).

    Parameters
    ----------
    body
        The rank's local :class:`~pdfem.pd.body.IceBody` (owned and halo particles).
    owned
        (n_local,) bool, the particles this rank owns.
    exchange
        Overwrites the halo entries of a per-particle array with their owners' values.
    comm
        The communicator (its ``allgather``).
    """
    mat = body.material
    args = (body.row_ptr, body.nbr, body.xi_len, body.weight)
    vol, ws = body.vol, body._ws
    s = family_sum(*args, vol, 1, ws)
    c = 18.0 * mat.K / (math.pi * body.delta ** 4)
    smax = float(s[owned].max()) if owned.any() else 0.0
    m = family_sum(*args, vol, 0, ws)
    exchange(m)
    inv_m = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0.0)
    sum_v = family_sum(*args, vol, 3, ws)
    sum_vm = family_sum(*args, vol * inv_m, 3, ws)
    lam = (30.0 * mat.mu / mat.density) * (inv_m * sum_v + sum_vm)
    kb = mat.K - 5.0 * mat.mu / 3.0
    if kb > 0.0:
        A = 3.0 * inv_m * family_sum(*args, vol, 2, ws)
        exchange(A)
        S = family_sum(*args, 6.0 * vol * inv_m * A, 2, ws)
        lam += (kb / mat.density) * (2.0 * A * A + S)
    lmax = float(lam[owned].max()) if owned.any() else 0.0
    parts = comm.allgather((smax, lmax))
    smax = max(p[0] for p in parts)
    lmax = max(p[1] for p in parts)
    bond = math.sqrt(2.0 * mat.density / (c * smax)) if smax > 0.0 else math.inf
    lps = 2.0 / math.sqrt(lmax) if lmax > 0.0 else math.inf
    return min(bond, lps)
