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


def kinetic_correction(body, step: float) -> float:
    """Velocity Verlet's own share of the kinetic energy of the whole body (J) at the step
    ``step`` (s): ``-(h^2 / 8) sum_i rho V_i |a_i|^2`` over the particles the scheme integrates
    (not the fixed or prescribed ones), ``a = f / rho + g`` the acceleration of the current
    forces.

    Added to ``1/2 m |v|^2`` it gives ``1/2 m v(n - 1/2) . v(n + 1/2)``, the kinetic energy
    that velocity Verlet conserves exactly with the strain energy for linear forces (the
    half-step velocities are ``v(n) -/+ (h/2) a(n)``; the same identity as the central
    difference scheme's, :meth:`pdfem.fem.explicit.CentralDifference.kinetic_correction`;
    Hairer, Lubich & Wanner, *Geometric Numerical Integration*, 2nd ed. 2006, ch. I.1.4 and
    IX.8: the scheme conserves a modified energy, not the sampled one). Without it an impact
    that sets the particles ringing in their highest modes shows up to a few percent of the
    energy in play as "created" while the ringing lasts. It is bounded and vanishes as h -> 0."""
    rho = body.material.density
    a = body.f / rho + body.gravity
    w = body.vol * (~body.fixed)
    if body.constraints:
        w = w.copy()
        for c in body.constraints:
            w[c.index] = 0.0
    return -0.125 * step * step * rho * float(body.layout.owned_sum(w * np.einsum("ij,ij->i", a, a)))


def strain_energy(body, forces_current: bool = False) -> float:
    """Elastic energy (J) of the whole body at the current positions: the unbroken bonds, with
    the dilatation of the current bond set (bonds broken this step excluded), and the crushed
    bonds that still push (:mod:`pdfem.pd.failure.crushed_shear`).

    With ``forces_current`` the body's own dilatation ``theta`` is taken instead of a
    dilatation pass: right when the last force computation was at the current positions and
    broke no bond (so after every time step, which recomputes the forces once bonds broke, and
    after a restart, which restores ``theta``); the pair loop made it with the same kernel, so
    the same bits (the full-family reference loop sums in another order and takes its pass).
    Not quite with a path constraint: it puts its particles back on the path after the pass,
    so ``theta`` near them is that of positions off by round-off (the bond lengths, below, are
    then taken afresh). The bond lengths that step's pass kept are read too where they are
    still current (not after a restart or a path constraint's move): again the same bits."""
    mat, b, lay = body.material, body.bonds, body.layout
    lengths = None
    if forces_current and body.family is None:
        theta = body.theta.copy()
        if body.workspace.lengths_current:  # the step's bond lengths, kept at these positions
            lengths = body.workspace.bond_length
    else:
        theta = np.empty(body.n)
        kernels.dilatation(body.y, b.row_ptr, b.nbr, b.xi_len, b.weight, SIGNED, body.vol,
                           body.m, theta, body.workspace)
    lay.exchange(theta)
    W = kernels.strain_energy(body.y, b.row_ptr, b.nbr, b.xi_len, b.weight, SIGNED, body.vol,
                              body.m, theta, mat.K, mat.mu, body.workspace, lengths)
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
