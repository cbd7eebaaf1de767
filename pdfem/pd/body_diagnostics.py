"""Diagnostics of an ice body: displacement, damage, kinetic and strain energy, momentum.

:class:`BodyDiagnostics` is mixed into :class:`pdfem.pd.body.IceBody` (whole body, one rank);
SI units (m, J, kg m/s).
"""

from __future__ import annotations

import numpy as np

from pdfem.pd.bonds import kernels
from pdfem.pd.failure.crushed_shear import shear_energy_args


class BodyDiagnostics:
    """What output and the energy balance read from an ice body."""

    def displacement(self) -> np.ndarray:
        """(N,3) displacement y - x0, m."""
        return self.y - self.x0

    def damage(self) -> np.ndarray:
        """(N,) broken fraction of each particle's initial bonds."""
        return kernels.damage(self.row_ptr, self.nbr, self._broken_arg(), self.n, self._ws,
                              self.weight)

    def kinetic_energy(self) -> float:
        """Kinetic energy, J."""
        return 0.5 * self.material.density * float(np.sum(self.vol * np.einsum("ij,ij->i", self.v, self.v)))

    def strain_energy(self) -> float:
        """Elastic energy of the unbroken bonds at the current positions, and of the broken
        bonds that still push (crushed ice), J."""
        mat = self.material
        theta = np.empty(self.n)  # of the current bond set (bonds broken this step excluded)
        br = self._broken_arg()
        kernels.dilatation(self.y, self.row_ptr, self.nbr, self.xi_len, self.weight, br,
                           self.vol, self.m, theta, self._ws)
        W = kernels.strain_energy(self.y, self.row_ptr, self.nbr, self.xi_len, self.weight,
                                  br, self.vol, self.m, theta, mat.K, mat.mu, self._ws)
        crushed = 0.0 if self.rest is None else kernels.contact_bond_energy(
            self.y, self.row_ptr, self.nbr, self.xi_len, self.weight, br, self.rest, self.vol,
            self.m, mat.mu, **shear_energy_args(self.shear))
        return float(np.dot(W, self.vol)) + crushed

    def momentum(self) -> np.ndarray:
        """Linear momentum (3,), kg m/s."""
        return self.material.density * (self.vol @ self.v)
