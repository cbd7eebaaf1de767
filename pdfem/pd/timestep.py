"""Stable time steps of explicit (velocity-Verlet) integration of the LPS.

Three estimates, from cheap to exact:

- :func:`stable_time_step` without ``mu``: Silling & Askari's (2005) estimate, the Gershgorin
  bound of the bond-based model. Safe for bulky bodies (the true LPS step is 1.1-2.2 times it)
  but not for bodies one or two particles thick.
- :func:`stable_time_step` with ``mu``: the Gershgorin bound of the linearised LPS itself,
  guaranteed safe for every body shape (about half the true step).
- :func:`max_eigenvalue_time_step`: the true critical step from the largest eigenvalue of the
  linearised system (Lanczos iteration), a check rather than a per-run step for large bodies.

:func:`body_stable_time_step` is the step an :class:`~pdfem.pd.body.IceBody` runs with: the
smaller of the first two, over the whole body whatever its layout (a rank's part has the whole
family of each owned particle, but its halo particles do not, so the halo's weighted volumes m_j
and family sums A_j that the bounds read are taken from their owners; the per-particle bound is
then the serial one for every owned particle, and the step the smallest over all ranks).

All three include the bond weights omega = w beta (:mod:`pdfem.pd.bonds.influence`).
"""

from __future__ import annotations

import math

import numpy as np

from pdfem.pd.bonds.pair_loop import dilatation, family_sum, forces
from pdfem.pd.bonds.workspace import PairWorkspace, workspace_for


def stable_time_step(
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    vol: np.ndarray,
    delta: float,
    density: float,
    K: float,
    mu: float | None = None,
    ws: PairWorkspace | None = None,
) -> float:
    """Stable explicit (velocity Verlet) time step (s).

    Without ``mu``: the estimate of Silling & Askari (2005),
    ``min_i sqrt(2 rho / sum_j omega V_j c / |xi|)`` with the bond-based micromodulus
    ``c = 18 K / (pi delta^4)``. It is the Gershgorin bound of the bond-based model, not of the
    LPS. Checked against the largest eigenvalue of the linearised LPS system
    (:func:`max_eigenvalue_time_step`), delta = 3.015 dx, bodies from
    :meth:`pdfem.pd.body.IceBody.from_shape` (cubic influence function, surface correction):
    on a 12^3 block it is 0.84 (nu = 0), 0.53 (nu = 0.3) and 0.44 (nu = 0.45) of the true
    critical step, so it is safe for bulky bodies. It is NOT safe for bodies only one or two
    particles thick (the LPS normalises every family by its weighted volume, so thin bodies keep
    bulk-like stiffness while the bond-based sum drops): 1.68, 1.13 and 0.96 times the true step
    on a 20 x 20 x 2 plate, 2.8, 1.7 and 1.3 times on a 16 x 16 x 1 sheet.

    With ``mu`` (recommended): the Gershgorin bound of the linearised LPS itself, which is
    below the true critical step for every body shape and 0 <= nu < 0.5: with
    ``k_ij = 15 mu (1/m_i + 1/m_j)`` (the shear part of W; the bulk part is
    ``(K - 5 mu/3) theta^2 / 2`` and only counts when positive, nu > 1/4)::

        lambda_i = (2/rho) sum_j k_ij omega V_j
                   + (max(K - 5 mu/3, 0)/rho) (2 A_i^2 + sum_j (6/m_j) |xi| omega V_j A_j),
        A_i = (3/m_i) sum_j |xi| omega V_j,       dt = 2 / sqrt(max_i lambda_i).

    Measured on the same bodies: 0.51, 0.51 and 0.43 of the true step on the 12^3 block, 0.46-0.60
    on the plate and the sheet (with w = 1 and no surface correction: 0.40-0.50 on blocks of 6^3
    to 24^3, 0.46-0.79 on sheets and rods).

    Parameters
    ----------
    row_ptr, nbr, xi_len, weight, vol
        Pair list (all initial bonds), bond lengths (m), bond weights (float32), volumes (m^3).
    delta
        Horizon (m), for the bond-based micromodulus.
    density
        Mass density (kg/m^3).
    K
        Bulk modulus (Pa).
    mu
        Shear modulus (Pa); selects the LPS bound.
    ws
        Optional :class:`PairWorkspace`.

    Returns
    -------
    float
        The time step (s); ``inf`` when there are no bonds.
    """
    ws = workspace_for(ws, row_ptr, nbr)
    if ws.n == 0 or ws.n_pairs == 0:
        return math.inf
    if mu is None:
        s = family_sum(row_ptr, nbr, xi_len, weight, vol, 1, ws)
        c = 18.0 * K / (math.pi * delta**4)
        return math.sqrt(2.0 * density / (c * float(s.max())))
    m = family_sum(row_ptr, nbr, xi_len, weight, vol, 0, ws)
    inv_m = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0.0)
    sum_v = family_sum(row_ptr, nbr, xi_len, weight, vol, 3, ws)
    sum_vm = family_sum(row_ptr, nbr, xi_len, weight, vol * inv_m, 3, ws)
    lam = (30.0 * mu / density) * (inv_m * sum_v + sum_vm)
    kb = K - 5.0 * mu / 3.0
    if kb > 0.0:
        A = 3.0 * inv_m * family_sum(row_ptr, nbr, xi_len, weight, vol, 2, ws)
        S = family_sum(row_ptr, nbr, xi_len, weight, 6.0 * vol * inv_m * A, 2, ws)
        lam += (kb / density) * (2.0 * A * A + S)
    lmax = float(lam.max())
    return 2.0 / math.sqrt(lmax) if lmax > 0.0 else math.inf


def body_stable_time_step(body) -> float:
    """A stable velocity-Verlet step (s) for an ice body, safe for every body shape: the
    smaller of Silling & Askari's estimate and the Gershgorin bound of the linearised LPS
    (:func:`stable_time_step` without and with ``mu``), both with the bond weights, over the
    whole body (collective). The Gershgorin bound is guaranteed below the true critical step
    for any shape; Silling & Askari's estimate is not for bodies one or two particles thick,
    and it only wins (is smaller) on bodies where it is safe. No further safety factor."""
    mat, b, lay = body.material, body.bonds, body.layout
    args = (b.row_ptr, b.nbr, b.xi_len, b.weight)
    vol, ws, owned = body.vol, body.workspace, lay.owned
    s = family_sum(*args, vol, 1, ws)
    c = 18.0 * mat.K / (math.pi * body.delta ** 4)
    smax = float(s[owned].max()) if owned.any() else 0.0
    m = family_sum(*args, vol, 0, ws)
    lay.exchange(m)
    inv_m = np.divide(1.0, m, out=np.zeros_like(m), where=m > 0.0)
    sum_v = family_sum(*args, vol, 3, ws)
    sum_vm = family_sum(*args, vol * inv_m, 3, ws)
    lam = (30.0 * mat.mu / mat.density) * (inv_m * sum_v + sum_vm)
    kb = mat.K - 5.0 * mat.mu / 3.0
    if kb > 0.0:
        A = 3.0 * inv_m * family_sum(*args, vol, 2, ws)
        lay.exchange(A)
        S = family_sum(*args, 6.0 * vol * inv_m * A, 2, ws)
        lam += (kb / mat.density) * (2.0 * A * A + S)
    lmax = float(lam[owned].max()) if owned.any() else 0.0
    parts = lay.comm.allgather((smax, lmax))
    smax = max(p[0] for p in parts)
    lmax = max(p[1] for p in parts)
    bond = math.sqrt(2.0 * mat.density / (c * smax)) if smax > 0.0 else math.inf
    lps = 2.0 / math.sqrt(lmax) if lmax > 0.0 else math.inf
    return min(bond, lps)


def max_eigenvalue_time_step(
    y: np.ndarray,
    row_ptr: np.ndarray,
    nbr: np.ndarray,
    xi_len: np.ndarray,
    weight: np.ndarray,
    broken: np.ndarray,
    vol: np.ndarray,
    m: np.ndarray,
    K: float,
    mu: float,
    dx: float,
    density: float,
    rel_step: float = 1e-6,
    tol: float = 1e-6,
    ws: PairWorkspace | None = None,
) -> float:
    """True critical step ``2 / sqrt(lambda_max)`` of the LPS system linearised at ``y`` (s).

    ``lambda_max`` is the largest eigenvalue of ``M^-1 Kt`` (``M = rho V``, ``Kt`` the tangent
    stiffness ``-d(V L)/dy``), found by Lanczos iteration (ARPACK ``eigsh``, the Krylov
    refinement of power iteration) on the symmetric form ``M^-1/2 Kt M^-1/2``. Each product is a
    central finite difference of two force evaluations (dilatation + forces, no breaking) with
    displacements of ``rel_step * dx``; expect some tens to a few hundred force evaluations, so
    it is cheap for small bodies and a check (not a per-run step) for large ones. No particle is
    held fixed, which can only raise ``lambda_max`` (a safe side).

    Parameters
    ----------
    y
        (N, 3) positions about which to linearise (m), usually the reference positions.
    row_ptr, nbr, xi_len, weight, broken, vol, m
        As in :func:`pdfem.pd.bonds.pair_loop.forces` (``broken`` is read, never changed).
    K, mu
        Bulk and shear modulus (Pa).
    dx
        Lattice spacing (m), the scale of the finite-difference displacements.
    density
        Mass density (kg/m^3).
    rel_step
        Finite-difference displacement relative to dx.
    tol
        Relative tolerance of the eigenvalue.
    ws
        Optional :class:`PairWorkspace`.

    Returns
    -------
    float
        The critical time step of velocity Verlet / central differences (s).
    """
    from scipy.sparse.linalg import LinearOperator, eigsh

    ws = workspace_for(ws, row_ptr, nbr)
    n = ws.n
    h = rel_step * dx
    sq = np.sqrt(vol / density)  # sqrt(V / rho)
    inv_sqm = 1.0 / np.sqrt(density * vol)  # 1 / sqrt(rho V)
    nofail = np.ones(n, dtype=np.uint8)
    theta = np.empty(n)
    fp = np.empty((n, 3))
    fm = np.empty((n, 3))
    yp = np.empty((n, 3))

    def force_at(u, out):
        np.add(y, u, out=yp)
        dilatation(yp, row_ptr, nbr, xi_len, weight, broken, vol, m, theta, ws)
        forces(yp, row_ptr, nbr, xi_len, weight, broken, vol, m, theta, K, mu, math.inf, nofail,
               out, ws)

    def matvec(x):
        u = (x.reshape(n, 3) * inv_sqm[:, None]) * h
        force_at(u, fp)
        force_at(-u, fm)
        return (-(fp - fm) / (2.0 * h) * sq[:, None]).ravel()

    op = LinearOperator((3 * n, 3 * n), matvec=matvec, dtype=np.float64)
    v0 = np.random.default_rng(0).standard_normal(3 * n)
    lam = float(eigsh(op, k=1, which="LA", tol=tol, v0=v0, return_eigenvectors=False)[0])
    return 2.0 / math.sqrt(lam) if lam > 0.0 else math.inf
