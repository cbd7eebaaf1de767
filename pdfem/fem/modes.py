"""Natural frequencies and mode shapes of an elastic structure with its supports.

The generalised eigenproblem ``K phi = omega^2 M phi`` with the assembled stiffness K (N/m)
and the lumped (diagonal) mass M (kg) of :class:`pdfem.fem.structure.ElasticStructure` is
solved on the free DOFs (the supports' Dirichlet DOFs are removed) by the Lanczos method of
ARPACK in shift-invert mode (:func:`scipy.sparse.linalg.eigsh` with ``sigma``, ``which="LM"``):
the eigenvalues nearest the shift converge first, so the lowest modes come out after a single
sparse LU factorisation of ``K - sigma M``. The shift is slightly negative so that a
free-floating structure (rigid-body modes, omega = 0) still gives a regular factorisation.
The start vector is fixed, so the result is deterministic. Frequencies are in Hz
(``f = omega / 2 pi``), shapes are mass-normalised (``phi . M phi = 1``, in m kg^-1/2) and
sorted by frequency. SI units throughout.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh

if TYPE_CHECKING:
    from pdfem.fem.structure import ElasticStructure


def shift_for(stiffness: sp.spmatrix, mass: np.ndarray) -> float:
    """A small negative shift (1/s^2) for shift-invert: ``-1e-6`` times the mean diagonal of
    ``M^-1 K``, below every eigenvalue (K is positive semi-definite), so ``K - sigma M`` is
    positive definite even with rigid-body modes."""
    scale = float(np.mean(stiffness.diagonal() / mass)) if mass.size else 1.0
    return -1e-6 * max(scale, 1e-300)


def generalized_modes(stiffness: sp.spmatrix, mass: np.ndarray, n: int,
                      seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The ``n`` lowest eigenpairs of ``K phi = lam M phi`` with diagonal M.

    Parameters
    ----------
    stiffness
        Symmetric positive semi-definite stiffness K (N/m), sparse (m, m).
    mass
        Lumped mass (kg), (m,), all > 0.
    n
        Number of modes, 1 <= n < m.
    seed
        Seed of the fixed start vector (same seed, same result).

    Returns
    -------
    lam, phi
        Eigenvalues ``omega^2`` (1/s^2), ascending, (n,) (round-off negatives clipped to 0),
        and mass-normalised eigenvectors (m, n).

    Raises
    ------
    ValueError
        If ``n`` is not in 1 .. m - 1.
    """
    m = stiffness.shape[0]
    if not 1 <= n < m:
        raise ValueError(f"the number of modes must be between 1 and {m - 1} (the free DOFs "
                         f"less one), got {n}")
    mass = np.asarray(mass, dtype=np.float64)
    k = sp.csc_matrix(stiffness)
    v0 = np.random.default_rng(seed).uniform(0.5, 1.5, m)
    lam, phi = eigsh(k, k=n, M=sp.diags(mass).tocsc(), sigma=shift_for(k, mass), which="LM",
                     v0=v0)
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    norms = np.sqrt(np.einsum("ij,i,ij->j", phi, mass, phi))
    phi = phi / norms
    # a fixed sign: the largest-magnitude component of each shape is positive
    big = phi[np.argmax(np.abs(phi), axis=0), np.arange(n)]
    phi = phi * np.where(big < 0.0, -1.0, 1.0)
    return np.clip(lam, 0.0, None), phi


def natural_modes(structure: ElasticStructure, n: int = 10) -> tuple[np.ndarray, np.ndarray]:
    """The first ``n`` natural frequencies and mode shapes of an elastic structure, with its
    supports (clamped and prescribed groups held at zero).

    Parameters
    ----------
    structure
        The structure (its ``K``, lumped mass ``solver.m``, free-DOF mask ``solver.free`` and
        ``dofmap``).
    n
        Number of modes (>= 1 and fewer than the free DOFs).

    Returns
    -------
    frequencies_hz, shapes
        (n,) natural frequencies (Hz), ascending, and (n, Nn, 3) mass-normalised nodal mode
        shapes (zero at the supports).

    Raises
    ------
    ValueError
        If ``n`` is out of range.
    """
    free = structure.solver.free
    k = sp.csr_matrix(structure.K)[free][:, free]
    lam, phi = generalized_modes(k, structure.solver.m[free], n)
    shapes = np.zeros((n, structure.dofmap.n_nodes, 3))
    full = np.zeros(structure.dofmap.n_dofs)
    for i in range(n):
        full[free] = phi[:, i]
        shapes[i] = structure.dofmap.to_nodal(full)
    return np.sqrt(lam) / (2.0 * math.pi), shapes
