"""The structures' stiffness product by node blocks (:mod:`pdfem.fem.node_blocks`).

Reference: scipy's CSR product ``K @ x``, bit for bit (each row summed in storage order from
zero, as scipy sums it), on one and two numba threads, by the serial and the parallel kernel,
alone and paired with a second matrix on the same pattern; scipy's own product for a matrix
without node blocks.
"""

from __future__ import annotations

import numba
import numpy as np
import pytest
import scipy.sparse as sp

from pdfem.fem import node_blocks
from pdfem.fem.elasticity import ElasticMaterial, stiffness_matrix
from pdfem.fem.fe_space import fe_space
from pdfem.fem.mesh import load_mesh
from pdfem.fem.node_blocks import NodeBlockOperator, NodeBlockPair


def _on_threads(n, fn):
    before = numba.get_num_threads()
    numba.set_num_threads(min(n, numba.config.NUMBA_NUM_THREADS))
    try:
        return fn()
    finally:
        numba.set_num_threads(before)


@pytest.mark.parametrize("order", [1, 2])
@pytest.mark.parametrize("parallel_from", [0, 10**9])
def test_stiffness_product_has_scipy_s_bits(order, parallel_from, gmsh_box, tmp_path,
                                            monkeypatch):
    """Hexahedra of order 1 and 2 (3 DOFs per node, node by node): K u has scipy's bits on
    1 and 2 threads, by the parallel kernel and by the serial one."""
    monkeypatch.setattr(node_blocks, "PARALLEL_BLOCKS", parallel_from)
    mesh = load_mesh(gmsh_box(tmp_path / "b.msh", (0.3, 0.1, 0.04), volume_groups=["solid"],
                              divisions=(6, 2, 2)))
    K = stiffness_matrix(fe_space(mesh, order=order).basis, ElasticMaterial(7850.0, 210e9, 0.3))
    op = NodeBlockOperator(K)
    assert op.blocks is not None
    u = np.random.default_rng(order).normal(size=K.shape[0]) * 1e-3
    for n in (1, 2):
        assert np.array_equal(_on_threads(n, lambda: op @ u), K @ u)
    # a second matrix on the same pattern (a geometric stiffness: here a scaled, shifted K)
    # in the same pass: the bits of the two products
    K2 = sp.csr_matrix((np.cos(K.data) * K.data, K.indices, K.indptr), shape=K.shape)
    pair = NodeBlockPair(op, NodeBlockOperator(K2))
    assert pair.fused
    for n in (1, 2):
        a, b = _on_threads(n, lambda: pair @ u)
        assert np.array_equal(a, K @ u) and np.array_equal(b, K2 @ u)


def test_matrix_without_node_blocks_keeps_scipy_s_product():
    """A random sparse matrix (rows of a node with different columns) is not cut into blocks;
    the product is scipy's."""
    rng = np.random.default_rng(3)
    a = sp.random(300, 300, density=0.05, random_state=rng, format="csr")
    op = NodeBlockOperator(a)
    x = rng.normal(size=300)
    assert op.blocks is None and np.array_equal(op @ x, a @ x)
    pair = NodeBlockPair(op, op)
    assert not pair.fused and all(np.array_equal(y, a @ x) for y in pair @ x)
