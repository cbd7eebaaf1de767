"""Plate moduli of a peridynamic ice sheet: its bending, twisting and membrane stiffness against
Kirchhoff's, from the energies of imposed plate deformations (SI units, ratios dimensionless).

Why (design note)
-----------------
Level ice fails in bending, so a sheet of ice particles must bend like a plate of stiffness
D = E h^3 / (12 (1 - nu^2)). A lattice sheet a few particles thick is not a local plate: its
outermost particles carry most of the bending energy, but their families are cut by the faces,
so their bonds reach only inwards, where the bending strain is smaller, and the sheet's energy
is a midpoint sum over the layers (1 - 1/n^2 of the integral for n layers). This module measures
the result on the lattice itself, as the ice body builds it (:meth:`pdfem.pd.body.IceBody.from_shape`:
cubic influence function and surface correction): a slab of thickness h with ``layers``
particles through h is given the displacement fields of the three Kirchhoff plate modes
(Timoshenko & Woinowsky-Krieger 1959, *Theory of Plates and Shells*, ch. 1-2) and of a membrane
stretch, each with free faces (sigma_zz = 0)::

    cylindrical  u = (-k x z, 0, k x^2/2 + c k z^2/2),          c = nu/(1-nu)  W = D k^2 / 2
    twist        u = (-k y z, -k x z, k x y)                                   W = D (1-nu) k^2
    spherical    u = (-k x z, -k y z, k (x^2+y^2)/2 + 2 c k z^2/2)              W = D (1+nu) k^2
    membrane     u = (e x, 0, -c e z)                                          W = E h e^2 / (2 (1-nu^2))

(W per unit area of the middle surface), and the ratio of the peridynamic energy of the middle
columns (whose families are complete in the plane) to W is returned. An orthotropic plate with
energy ``(D11 (w_xx^2 + w_yy^2) + 2 D12 w_xx w_yy + 4 D66 w_xy^2) / 2`` gives the three ratios
``D11 / D``, ``(D11 + D12) / ((1 + nu) D)`` and ``2 D66 / ((1 - nu) D)``; an isotropic Kirchhoff
plate gives 1, 1, 1. The imposed fields are not relaxed, so each ratio is an upper bound of the
sheet's stiffness in that mode (relaxing the bending fields changes them by < 1 %; the membrane
field of a sheet two particles thick by 3 %). One energy evaluation per mode: milliseconds for a
few thousand particles.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pdfem.geometry.shapes import Box
from pdfem.pd.bonds import kernels
from pdfem.pd.body import IceBody
from pdfem.pd.materials.lps import IceMaterial

_E = 1.0e9        # Pa: any modulus (the ratios do not depend on it)
_CURVATURE = 1e-6  # 1/m on a sheet 1 m thick: small, so the energies are linear-elastic
_REACH = 4        # the sheet reaches this many horizons from the middle columns (module doc)


@dataclass(frozen=True)
class PlateModuli:
    """Stiffness of a peridynamic sheet against Kirchhoff's plate, per mode (dimensionless).

    Attributes
    ----------
    cylindrical, twist, spherical, membrane
        Energy ratios of the imposed modes (module doc).
    poisson_ratio
        nu of the material.
    """

    cylindrical: float
    twist: float
    spherical: float
    membrane: float
    poisson_ratio: float

    @property
    def d11(self) -> float:
        """D11 / D of the equivalent orthotropic plate."""
        return self.cylindrical

    @property
    def d12(self) -> float:
        """D12 / D (nu for an isotropic plate)."""
        return self.spherical * (1.0 + self.poisson_ratio) - self.cylindrical

    @property
    def d66(self) -> float:
        """D66 / D ((1 - nu) / 2 for an isotropic plate)."""
        return 0.5 * self.twist * (1.0 - self.poisson_ratio)


def _fields(x: np.ndarray, nu: float, k: float) -> dict[str, tuple[np.ndarray, float]]:
    """The imposed displacements (m) and their Kirchhoff energy per area (J/m^2) for a sheet
    1 m thick (module doc)."""
    X, Y, Z = x.T
    c = nu / (1.0 - nu)
    d = _E / (12.0 * (1.0 - nu * nu))
    cyl = np.stack([-k * X * Z, 0.0 * X, 0.5 * k * X**2 + 0.5 * c * k * Z**2], 1)
    twist = np.stack([-k * Y * Z, -k * X * Z, k * X * Y], 1)
    sph = np.stack([-k * X * Z, -k * Y * Z, 0.5 * k * (X**2 + Y**2) + c * k * Z**2], 1)
    mem = np.stack([k * X, 0.0 * X, -c * k * Z], 1)
    return {"cylindrical": (cyl, 0.5 * d * k * k), "twist": (twist, d * (1.0 - nu) * k * k),
            "spherical": (sph, d * (1.0 + nu) * k * k),
            "membrane": (mem, 0.5 * _E * k * k / (1.0 - nu * nu))}


def plate_moduli(layers: int, horizon_factor: float, poisson_ratio: float = 0.3,
                 surface_correction: bool = True) -> PlateModuli:
    """Bending, twisting and membrane stiffness of a lattice ice sheet against a Kirchhoff plate.

    Parameters
    ----------
    layers
        Particles through the thickness, n = h / dx (>= 1).
    horizon_factor
        delta / dx (as the ice body's ``horizon / dx``).
    poisson_ratio
        nu of the ice.
    surface_correction
        Build the sheet with the surface correction of the bond weights (as every case-file
        body is; :mod:`pdfem.pd.bonds.surface`).

    Returns
    -------
    PlateModuli
        The energy ratios of the imposed modes (module doc); the sheet is 1 m thick (the ratios
        depend only on ``layers``, ``horizon_factor`` and ``poisson_ratio``).

    Raises
    ------
    ValueError
        If ``layers`` < 1.
    """
    if layers < 1:
        raise ValueError(f"a sheet needs at least one particle layer, got layers = {layers}")
    dx = 1.0 / layers
    delta = horizon_factor * dx
    half = dx * (_REACH * np.floor(horizon_factor) + 2.0)  # far from the side faces
    mat = IceMaterial(density=900.0, youngs_modulus=_E, poisson_ratio=poisson_ratio)
    body = IceBody.from_shape("sheet", Box((-half, -half, -0.5), (half, half, 0.5)), mat, dx,
                              delta, surface_correction=surface_correction)
    x = body.x0
    middle = (np.abs(x[:, 0]) < 0.5 * dx + 1e-9) & (np.abs(x[:, 1]) < 0.5 * dx + 1e-9)
    area = middle.sum() / layers * dx * dx
    broken = np.zeros(body.n_bonds, dtype=np.uint8)
    theta = np.zeros(body.n)
    ratios = {}
    for name, (u, ref) in _fields(x, poisson_ratio, _CURVATURE).items():
        y = np.ascontiguousarray(x + u)
        kernels.dilatation(y, body.row_ptr, body.nbr, body.xi_len, body.weight, broken, body.vol,
                           body.m, theta, body.workspace)
        w = kernels.strain_energy(y, body.row_ptr, body.nbr, body.xi_len, body.weight, broken,
                                  body.vol, body.m, theta, mat.K, mat.mu, body.workspace)
        ratios[name] = float((w[middle] * body.vol[middle]).sum() / area / ref)
    return PlateModuli(poisson_ratio=poisson_ratio, **ratios)
