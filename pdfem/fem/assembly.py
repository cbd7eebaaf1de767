"""Element-by-element assembly of the bilinear forms of a vector basis, vectorised.

scikit-fem's ``asm`` evaluates a form once per pair of local basis functions: 3,600 Python
calls for a 20-node serendipity hexahedron, which took 7 s for the demo's 0.08 m hull panel.
Here the forms are written over every local function at once: the gradients of all local
functions in a block of elements are one array, and the element matrices are batched matrix
sums over the quadrature points in numba kernels, element by element. The result is the same
sparse matrix (to round-off: the products are summed in another order), in the basis' DOF
order, built in a fraction of a second. Each element matrix is summed in a fixed order by one
thread, so the matrix is the same bits on any number of threads or ranks (a BLAS product is
not: its blocking depends on the threads and the arrays' alignment).

The elements are taken in blocks, so that the gradients held at a time stay near
``BLOCK_BYTES``, whatever the mesh.
"""

from __future__ import annotations

from typing import Callable

import numba
import numpy as np
from numba import prange
import scipy.sparse as sp
import skfem

BLOCK_BYTES = 2 * 2**20
"""Bytes of the gradient array of one block of elements (nloc x 3 x 3 x elements x points)."""


def local_gradients(basis: skfem.CellBasis, elements: slice) -> np.ndarray:
    """Gradients ``G[e, q, a, i, j] = d phi_a,i / dx_j`` of every local vector function ``a`` of
    the basis over the given elements, (ne, nq, nloc, 3, 3)."""
    g = np.stack([np.asarray(b[0].grad)[:, :, elements] for b in basis.basis])
    return np.ascontiguousarray(g.transpose(3, 4, 0, 1, 2))


def local_values(basis: skfem.CellBasis) -> np.ndarray:
    """Values ``phi[a, i, e, q]`` of every local vector function ``a`` of the basis at the
    quadrature points of every element, (nloc, 3, Ne, nq)."""
    return np.array([np.asarray(b[0]) for b in basis.basis])


def assemble_vector(basis: skfem.CellBasis, per_element: np.ndarray) -> np.ndarray:
    """The global DOF vector (N,) that sums the element entries ``per_element`` (nloc, Ne) of
    every element's local DOFs."""
    return np.bincount(basis.element_dofs.ravel(), per_element.ravel(), minlength=basis.N)


def assemble(basis: skfem.CellBasis,
             element_matrices: Callable[[np.ndarray, np.ndarray, slice], np.ndarray]
             ) -> sp.csr_matrix:
    """The global CSR matrix of a bilinear form given element by element.

    Parameters
    ----------
    basis
        A vector basis (``ElementVector`` of any scalar element).
    element_matrices
        ``(G, dx, elements) -> (ne, nloc, nloc)``: the element matrices of the elements in the
        slice ``elements`` from their local gradients ``G`` (:func:`local_gradients`) and the
        quadrature weights ``dx`` (ne, nq) (m^3). Row ``a``, column ``b``: the form with the
        test function ``a`` and the trial function ``b``.

    Returns
    -------
    scipy.sparse.csr_matrix
        (N, N), duplicates summed, indices sorted.
    """
    dofs = basis.element_dofs                                       # (nloc, Ne)
    nloc, n_el = dofs.shape
    per_element = nloc * 9 * basis.dx.shape[1] * 8
    size = max(1, BLOCK_BYTES // per_element)
    data = np.empty((n_el, nloc, nloc))
    for start in range(0, n_el, size):
        sl = slice(start, min(start + size, n_el))
        data[sl] = element_matrices(local_gradients(basis, sl), basis.dx[sl], sl)
    rows = np.broadcast_to(dofs.T[:, :, None], data.shape)
    cols = np.broadcast_to(dofs.T[:, None, :], data.shape)
    K = sp.coo_matrix((data.ravel(), (rows.ravel(), cols.ravel())),
                      shape=(basis.N, basis.N)).tocsr()
    K.sum_duplicates()
    K.sort_indices()
    return K


@numba.njit(parallel=True, cache=True)
def _elasticity_kernel(G, dx, lam, mu, out):
    """out[e] = sum_q dx[e, q] (lam tr(eps_a) tr(eps_b) + 2 mu eps_a : eps_b) over the local
    functions a, b (Voigt strains; each element by one thread, in a fixed order)."""
    ne, nq, nloc = G.shape[0], G.shape[1], G.shape[2]
    for e in prange(ne):
        eps = np.empty((nloc, 6))
        for a in range(nloc):
            for b in range(nloc):
                out[e, a, b] = 0.0
        for q in range(nq):
            w = dx[e, q]
            for a in range(nloc):
                g = G[e, q, a]
                eps[a, 0] = g[0, 0]
                eps[a, 1] = g[1, 1]
                eps[a, 2] = g[2, 2]
                eps[a, 3] = 0.5 * (g[0, 1] + g[1, 0])
                eps[a, 4] = 0.5 * (g[0, 2] + g[2, 0])
                eps[a, 5] = 0.5 * (g[1, 2] + g[2, 1])
            for a in range(nloc):
                ta = eps[a, 0] + eps[a, 1] + eps[a, 2]
                for b in range(a, nloc):
                    tb = eps[b, 0] + eps[b, 1] + eps[b, 2]
                    dd = (eps[a, 0] * eps[b, 0] + eps[a, 1] * eps[b, 1] + eps[a, 2] * eps[b, 2]
                          + 2.0 * (eps[a, 3] * eps[b, 3] + eps[a, 4] * eps[b, 4]
                                   + eps[a, 5] * eps[b, 5]))
                    out[e, a, b] += w * (lam * ta * tb + 2.0 * mu * dd)
        for a in range(nloc):
            for b in range(a + 1, nloc):
                out[e, b, a] = out[e, a, b]


@numba.njit(parallel=True, cache=True)
def _initial_stress_kernel(G, sigma, dx, out):
    """out[e] = sum_q dx[e, q] sigma_jk G[a, i, j] G[b, i, k] (each element by one thread)."""
    ne, nq, nloc = G.shape[0], G.shape[1], G.shape[2]
    for e in prange(ne):
        s = np.empty((nloc, 3, 3))
        for a in range(nloc):
            for b in range(nloc):
                out[e, a, b] = 0.0
        for q in range(nq):
            w = dx[e, q]
            sg = sigma[e, q]
            for a in range(nloc):
                for i in range(3):
                    for k in range(3):
                        s[a, i, k] = (G[e, q, a, i, 0] * sg[0, k] + G[e, q, a, i, 1] * sg[1, k]
                                      + G[e, q, a, i, 2] * sg[2, k])
            for a in range(nloc):
                for b in range(a, nloc):
                    acc = 0.0
                    for i in range(3):
                        for k in range(3):
                            acc += s[a, i, k] * G[e, q, b, i, k]
                    out[e, a, b] += w * acc
        for a in range(nloc):
            for b in range(a + 1, nloc):
                out[e, b, a] = out[e, a, b]


def elasticity_matrices(lam: float, mu: float) -> Callable:
    """Element stiffness ``int lambda tr(eps_a) tr(eps_b) + 2 mu eps_a : eps_b dV`` (N/m) of
    isotropic linear elasticity with the Lame constants ``lam``, ``mu`` (Pa), for
    :func:`assemble`."""

    def matrices(G: np.ndarray, dx: np.ndarray, elements: slice) -> np.ndarray:
        out = np.empty(G.shape[:1] + G.shape[2:3] * 2)
        _elasticity_kernel(G, np.ascontiguousarray(dx), float(lam), float(mu), out)
        return out

    return matrices


def initial_stress_matrices(sigma: np.ndarray) -> Callable:
    """Element initial-stress (geometric) stiffness
    ``int sigma0_jk dphi_a,i/dx_j dphi_b,i/dx_k dV`` (N/m) of the symmetric prestress ``sigma``
    (3, 3, Ne, nq) (Pa) at the basis' quadrature points, for :func:`assemble`."""

    def matrices(G: np.ndarray, dx: np.ndarray, elements: slice) -> np.ndarray:
        out = np.empty(G.shape[:1] + G.shape[2:3] * 2)
        s = np.ascontiguousarray(sigma[:, :, elements, :].transpose(2, 3, 0, 1))
        _initial_stress_kernel(G, s, np.ascontiguousarray(dx), out)
        return out

    return matrices
