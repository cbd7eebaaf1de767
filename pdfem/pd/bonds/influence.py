"""Bond weights of the LPS: influence function times partial-volume factor, one float32 per bond.

Every family sum of the LPS kernels (:mod:`pdfem.pd.bonds.pair_loop`) weighs bond k = (i, j) by
``omega_k V_j`` with the bond weight::

    omega_k = w(xi_k) beta(|xi_k|)

- ``beta`` is the partial-volume factor (Madenci & Oterkus 2014, *Peridynamic Theory and Its
  Applications*, Springer): the fraction of the particle cube of j inside the horizon,
  ``min(1, (delta + dx/2 - |xi|) / dx)`` (bonds exist up to delta, so beta >= 1/2);
- ``w`` is the influence function, which the LPS (Silling et al. 2007, "Peridynamic states and
  constitutive modeling", J. Elasticity 88) allows to be any positive function of the reference
  bond vector. pdfem uses ``w = 1`` for arbitrary point clouds and the cubic correction below on
  cubic lattices.

The weights are computed once per body (:func:`bond_weights`) and stored as float32 (4 bytes per
pair; with the int32 partner and the float64 reference length a pair costs 16 bytes). The
kernels read omega_k instead of recomputing beta, so they are independent of how the weight is
made.

Design note: why the influence function is not 1 on a cubic lattice
-------------------------------------------------------------------
For a uniform strain eps the LPS energy density of a particle with a complete family is
(linearised, e = |xi| n.eps.n, n = xi / |xi|, m = sum_j omega |xi|^2 V_j)::

    W = K theta^2 / 2 + (15 mu / 2m) sum_j omega |xi|^2 (n.eps.n - theta/3)^2 V_j

It equals the isotropic ``K theta^2 / 2 + mu eps_dev : eps_dev`` exactly when the second moment
``sum omega |xi|^2 n n V`` is ``(m/3) I`` (true for any cubic-symmetric weight on a cubic
lattice) and the fourth moment ``M4 = sum omega |xi|^2 n n n n V`` is isotropic,
``(m/15) (d_ij d_kl + d_ik d_jl + d_il d_jk)``. For a weight with cubic symmetry M4 has two
independent entries, ``A = M4_xxxx`` and ``B = M4_xxyy``, and is isotropic iff ``A = 3B``. With
w = 1 the lattice family of horizon delta = 3.015 dx has A / 3B = 0.870: the discrete model is
cubic, with E = 0.888 E_input and nu = 0.322 (for nu = 0.3) along the lattice axes, outside the
3 % the design asks for. The weight::

    w(xi) = 1 + g (n_x^4 + n_y^4 + n_z^4 - 3/5)

keeps cubic symmetry and averages to 1 over the sphere (the mean of sum n^4 is 3/5), and A and B
are linear in g, so ``A(g) = 3 B(g)`` has the closed-form solution of :func:`isotropy_gain`
(g = 1.017 at delta = 3.015 dx, 0.347 at 4.015 dx; the lattice sum includes beta). Then the
bulk LPS reproduces K and mu exactly under uniform strain. The weight enters m, theta and the
force state alike (everywhere omega appears), so the model stays hyperelastic.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import prange

_MEAN_N4 = 0.6  # mean of n_x^4 + n_y^4 + n_z^4 over the unit sphere


def partial_volume_factor(xi_len: np.ndarray, delta: float, dx: float) -> np.ndarray:
    """Partial-volume factor beta = min(1, (delta + dx/2 - |xi|) / dx) of bonds ``xi_len`` long.

    Parameters
    ----------
    xi_len
        Reference bond lengths (m), each at most ``delta``.
    delta, dx
        Horizon and lattice spacing (m).

    Returns
    -------
    ndarray
        float64 factors in [1/2, 1].
    """
    return np.minimum(1.0, (delta + 0.5 * dx - np.asarray(xi_len, dtype=np.float64)) / dx)


def cubic_influence(n: np.ndarray, gain: float) -> np.ndarray:
    """The cubic influence function w = 1 + g (n_x^4 + n_y^4 + n_z^4 - 3/5).

    Parameters
    ----------
    n
        (M, 3) unit bond directions.
    gain
        The gain g (:func:`isotropy_gain`); 0 gives w = 1.

    Returns
    -------
    ndarray
        (M,) float64 weights.
    """
    n = np.asarray(n, dtype=np.float64)
    return 1.0 + gain * (np.sum(n**4, axis=1) - _MEAN_N4)


def lattice_family(horizon_factor: float) -> np.ndarray:
    """The integer vectors v != 0 with |v| <= ``horizon_factor``: the family of a cubic lattice
    particle in units of dx (horizon delta = horizon_factor dx).

    Returns
    -------
    ndarray
        (M, 3) float64 lattice vectors.
    """
    r = int(math.floor(horizon_factor))
    a = np.arange(-r, r + 1, dtype=np.float64)
    v = np.stack(np.meshgrid(a, a, a, indexing="ij"), -1).reshape(-1, 3)
    ln2 = np.sum(v * v, axis=1)
    return v[(ln2 > 0.0) & (ln2 <= horizon_factor * horizon_factor)]


def isotropy_gain(horizon_factor: float) -> float:
    """The gain g of the cubic influence function that makes the lattice LPS isotropic.

    Solves ``A(g) = 3 B(g)`` for the fourth moments ``A = sum w |v|^2 beta n_x^4`` and
    ``B = sum w |v|^2 beta n_x^2 n_y^2`` over the lattice family (:func:`lattice_family`), with
    ``w = 1 + g q``, ``q = sum n^4 - 3/5`` and ``beta = min(1, horizon_factor + 1/2 - |v|)``.
    Both are linear in g: ``g = (3 B0 - A0) / (A1 - 3 B1)`` with ``A0 = sum |v|^2 beta n_x^4``,
    ``A1 = sum |v|^2 beta q n_x^4`` and B0, B1 alike.

    Parameters
    ----------
    horizon_factor
        delta / dx (> 1).

    Returns
    -------
    float
        The gain (dimensionless); about 1.017 for 3.015, 0.347 for 4.015.

    Raises
    ------
    ValueError
        If no positive weight of this form makes the family isotropic (horizons below about
        1.5 dx, where the family is too small).
    """
    v = lattice_family(float(horizon_factor))
    ln = np.linalg.norm(v, axis=1)
    n = v / ln[:, None] if len(v) else v
    base = ln**2 * np.minimum(1.0, horizon_factor + 0.5 - ln)
    q = np.sum(n**4, axis=1) - _MEAN_N4
    xx = n[:, 0] ** 4
    xy = n[:, 0] ** 2 * n[:, 1] ** 2
    A0, B0 = float(np.sum(base * xx)), float(np.sum(base * xy))
    A1, B1 = float(np.sum(base * q * xx)), float(np.sum(base * q * xy))
    den = A1 - 3.0 * B1
    g = (3.0 * B0 - A0) / den if den != 0.0 else math.nan
    if not (math.isfinite(g) and np.all(1.0 + g * q > 0.0)):
        raise ValueError(
            f"a horizon of {horizon_factor:g} dx is too small for an isotropic cubic-lattice model "
            "(no positive influence function makes its family's fourth moment isotropic); "
            "use a horizon of at least 1.5 dx (3.015 dx is usual)"
        )
    return g


@numba.njit(cache=True, parallel=True)
def _bond_weights(x, row_ptr, nbr, xi_len, hi, inv_dx, gain, out):
    for i in prange(row_ptr.shape[0] - 1):
        for k in range(row_ptr[i], row_ptr[i + 1]):
            j = nbr[k]
            ln = xi_len[k]
            w = 1.0
            if gain != 0.0:
                n0 = (x[j, 0] - x[i, 0]) / ln
                n1 = (x[j, 1] - x[i, 1]) / ln
                n2 = (x[j, 2] - x[i, 2]) / ln
                n0 *= n0
                n1 *= n1
                n2 *= n2
                w = 1.0 + gain * (n0 * n0 + n1 * n1 + n2 * n2 - _MEAN_N4)
            out[k] = w * min(1.0, (hi - ln) * inv_dx)


def bond_weights(
    x: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    delta: float,
    dx: float,
    gain: float = 0.0,
) -> np.ndarray:
    """Bond weights omega_k = w(xi_k) beta(|xi_k|) of a pair list, as float32.

    Parameters
    ----------
    x
        (N, 3) reference positions (m).
    row_ptr, nbr
        CSR unique pairs i < j (int64 (N+1,), int32 (P,)).
    xi_len
        (P,) reference bond lengths (m).
    delta, dx
        Horizon and lattice spacing (m) of the partial-volume factor.
    gain
        Gain g of the cubic influence function (:func:`isotropy_gain` for a cubic lattice
        aligned with the axes); 0 gives w = 1.

    Returns
    -------
    ndarray
        (P,) float32 bond weights (dimensionless).
    """
    out = np.empty(np.asarray(nbr).shape[0], dtype=np.float32)
    _bond_weights(np.ascontiguousarray(x, dtype=np.float64), row_ptr, nbr, xi_len,
                  float(delta) + 0.5 * float(dx), 1.0 / float(dx), float(gain), out)
    return out
