"""The vectorised element-by-element assembly gives scikit-fem's matrices.

Reference: ``skfem.asm`` of the same bilinear forms (scikit-fem's linear elasticity model and
the initial-stress form sigma0_jk du_i/dx_j dv_i/dx_k written as an skfem ``BilinearForm``) on
the same basis; they agree to round-off (1e-14 of the largest entry), for first- and
second-order tetrahedra and hexahedra. The lumped mass is the consistent mass' row sums,
which add up to the body's mass.
"""

from __future__ import annotations

import numpy as np
import pytest
import skfem
from skfem.models.elasticity import linear_elasticity

from pdfem.fem import assembly
from pdfem.fem.assembly import assemble, elasticity_matrices, initial_stress_matrices
from pdfem.fem.elasticity import lumped_mass


@skfem.BilinearForm
def _initial_stress(u, v, w):
    return np.einsum("jk...,ij...,ik...->...", w["sigma"], u.grad, v.grad)


@skfem.BilinearForm
def _mass(u, v, w):
    return 7850.0 * skfem.helpers.dot(u, v)


BASES = {
    "tet_p1": (skfem.MeshTet().refined(2), skfem.ElementTetP1(), 2),
    "tet_p2": (skfem.MeshTet().refined(1), skfem.ElementTetP2(), 4),
    "hex1": (skfem.MeshHex().refined(2), skfem.ElementHex1(), 3),
    "hex_s2": (skfem.MeshHex().refined(1), skfem.ElementHexS2(), 4),
}


@pytest.mark.parametrize("name", sorted(BASES))
def test_matrices_equal_skfem_assembly(name, monkeypatch):
    mesh, element, order = BASES[name]
    # distorted, so that the Jacobians differ from element to element
    mesh = skfem.MeshTet(mesh.p * [[0.3], [0.5], [0.2]] + 0.05 * np.sin(7 * mesh.p), mesh.t) \
        if isinstance(mesh, skfem.MeshTet) else \
        skfem.MeshHex(mesh.p * [[0.3], [0.5], [0.2]] + 0.02 * np.sin(5 * mesh.p), mesh.t)
    basis = skfem.Basis(mesh, skfem.ElementVector(element), intorder=order)
    monkeypatch.setattr(assembly, "BLOCK_BYTES", 1)  # one element per block: blocks join right
    lam, mu = 1.2e9, 0.8e9
    K_ref = skfem.asm(linear_elasticity(lam, mu), basis).tocsr()
    K = assemble(basis, elasticity_matrices(lam, mu))
    assert abs(K - K_ref).max() <= 1e-14 * abs(K_ref).max()
    rng = np.random.default_rng(3)
    sigma = rng.standard_normal((3, 3) + basis.dx.shape)
    sigma += sigma.transpose(1, 0, 2, 3)
    S_ref = skfem.asm(_initial_stress, basis, sigma=sigma).tocsr()
    S = assemble(basis, initial_stress_matrices(sigma))
    assert abs(S - S_ref).max() <= 1e-14 * abs(S_ref).max()
    if name in ("tet_p1", "hex1"):  # row-sum lumping: first-order elements only
        m_ref = np.asarray(skfem.asm(_mass, basis).sum(axis=1)).ravel()
        m = lumped_mass(basis, 7850.0)
        np.testing.assert_allclose(m, m_ref, rtol=1e-13)
        assert m.sum() == pytest.approx(3 * 7850.0 * basis.dx.sum(), rel=1e-13)


def test_same_bits_on_any_blocks_and_threads(monkeypatch):
    """The element matrices are summed element by element in a fixed order: the stiffness is
    the same bits whatever the block size or the number of threads (1 and N ranks agree)."""
    import numba

    mesh, element, order = BASES["hex_s2"]
    basis = skfem.Basis(mesh, skfem.ElementVector(element), intorder=order)
    form = elasticity_matrices(1.2e9, 0.8e9)
    K = assemble(basis, form)
    monkeypatch.setattr(assembly, "BLOCK_BYTES", 1)
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        K1 = assemble(basis, form)
    finally:
        numba.set_num_threads(threads)
    np.testing.assert_array_equal(K1.indptr, K.indptr)
    np.testing.assert_array_equal(K1.indices, K.indices)
    np.testing.assert_array_equal(K1.data, K.data)
