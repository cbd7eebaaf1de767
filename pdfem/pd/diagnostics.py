"""What output and the energy balance read from an ice body: damage, energies, momentum.

Functions of an :class:`~pdfem.pd.body.IceBody` (whole, or a rank's part): per-particle values
are the local ones (right for owned particles), totals are over the owned particles of every
process through the body's layout (correctly rounded, so the same on 1 and N ranks). SI units
(J, kg m/s).
"""

from __future__ import annotations

import numpy as np

from pdfem.pd.bonds import kernels
from pdfem.pd.bonds.pair_loop import SIGNED
from pdfem.pd.failure.crushed_shear import shear_energy_args


def damage(body) -> np.ndarray:
    """(n,) broken fraction of each local particle's initial bonds."""
    b = body.bonds
    return kernels.damage(b.row_ptr, b.nbr, SIGNED, body.n, body.workspace, b.weight)


def kinetic_energy(body) -> float:
    """Kinetic energy of the whole body, J."""
    vv = np.einsum("ij,ij->i", body.v, body.v)
    return 0.5 * body.material.density * float(body.layout.owned_sum(body.vol * vv))


def strain_energy(body, forces_current: bool = False) -> float:
    """Elastic energy (J) of the whole body at the current positions: the unbroken bonds, with
    the dilatation of the current bond set (bonds broken this step excluded), and the crushed
    bonds that still push (:mod:`pdfem.pd.failure.crushed_shear`).

    With ``forces_current`` the body's own dilatation ``theta`` is taken instead of a
    dilatation pass: right when the last force computation was at the current positions and
    broke no bond (so after every time step, which recomputes the forces once bonds broke, and
    after a restart, which restores ``theta``); the pair loop made it with the same kernel, so
    the same bits (the full-family reference loop sums in another order and takes its pass)."""
    mat, b, lay = body.material, body.bonds, body.layout
    if forces_current and body.family is None:
        theta = body.theta.copy()
    else:
        theta = np.empty(body.n)
        kernels.dilatation(body.y, b.row_ptr, b.nbr, b.xi_len, b.weight, SIGNED, body.vol,
                           body.m, theta, body.workspace)
    lay.exchange(theta)
    W = kernels.strain_energy(body.y, b.row_ptr, b.nbr, b.xi_len, b.weight, SIGNED, body.vol,
                              body.m, theta, mat.K, mat.mu, body.workspace)
    total = float(lay.owned_sum(W * body.vol))
    if body.rest is None:
        return total
    crushed = kernels.contact_bond_energy(body.y, b.row_ptr, b.nbr, b.xi_len, b.weight, SIGNED,
                                          body.rest, body.vol, body.m, mat.mu, owned=lay.owned,
                                          **shear_energy_args(body.shear))
    return total + float(lay.allsum(crushed))


def momentum(body) -> np.ndarray:
    """Linear momentum (3,) of the whole body, kg m/s."""
    return body.material.density * body.layout.owned_sum(body.vol[:, None] * body.v)
