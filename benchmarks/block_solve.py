"""The implicit blades' solves: :class:`pdfem.fem.block_factor.BlockFactor` (``L D L^T``, numba)
against SuperLU's own solves of the same blocks, in one run.

The matrix is the milling propeller's Newmark matrix ``A = M + dt^2/4 K`` on its free DOFs
(models/propeller.py as in models/propeller_ice_milling.toml: 10-node tetrahedra of 0.1 m,
14,031 free DOFs in 4 blocks, one per blade; dt = 13.8 us, the case's coupling step; without
the rotating frame's terms, which change the values, not the pattern). Timed: one right-hand
side (a coupling step's solve) and a batch of 96 (the contact compliance's probing,
:mod:`pdfem.fem.step_compliance`), the median of rounds of 100 and of 5 solves.

Run::

    python benchmarks/block_solve.py                       # numba's default threads
    NUMBA_NUM_THREADS=1 python benchmarks/block_solve.py   # one thread

SI units: s for the times.
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from threadpoolctl import threadpool_limits

from pdfem.fem.block_factor import BlockFactor

DT = 13.8e-6   # s


def blades_matrix() -> sp.csr_matrix:
    """The propeller's ``M + dt^2/4 K`` on its free DOFs."""
    import sys
    sys.path.insert(0, str(Path(__file__).parent))
    from blade_root_convergence import blade_model
    with tempfile.TemporaryDirectory() as tmp:
        s, _, _ = blade_model(0.1, 2, 0.0, Path(tmp))
    free = np.flatnonzero(s.solver.free)
    a = (sp.diags(s.solver.m) + 0.25 * DT * DT * s.solver.K).tocsr()
    return sp.csr_matrix(a[free][:, free])


def median_time(solve, b, repeats: int, rounds: int = 5) -> float:
    """Median over ``rounds`` of the mean time (s) of ``repeats`` calls ``solve(b)``."""
    solve(b)
    times = []
    for _ in range(rounds):
        t = time.perf_counter()
        for _ in range(repeats):
            solve(b)
        times.append((time.perf_counter() - t) / repeats)
    return float(np.median(times))


def main() -> int:
    a = blades_matrix()
    ldl = BlockFactor(a)
    blocks = ldl.blocks
    lus = [spla.splu(a[idx][:, idx].tocsc(), permc_spec="MMD_AT_PLUS_A",
                     options={"SymmetricMode": True}) for idx in blocks]

    def superlu(b):
        x = np.empty_like(b)
        for idx, lu in zip(blocks, lus):
            x[idx] = lu.solve(b[idx])
        return x

    rng = np.random.default_rng(0)
    one, batch = rng.standard_normal(a.shape[0]), rng.standard_normal((a.shape[0], 96))
    assert np.allclose(ldl.solve(one), superlu(one), rtol=1e-10, atol=0.0)
    print(f"{a.shape[0]} free DOFs in {len(blocks)} blocks; factors: L D L^T "
          f"{ldl.nbytes / 1e6:.1f} MB, SuperLU L + U "
          f"{sum(lu.L.nnz + lu.U.nnz for lu in lus) * 12 / 1e6:.1f} MB (8 B values, 4 B indices)")
    with threadpool_limits(limits=1, user_api="blas"):
        for label, b, n in (("one right-hand side", one, 100), ("96 right-hand sides", batch, 5)):
            t_ldl, t_slu = median_time(ldl.solve, b, n), median_time(superlu, b, n)
            print(f"{label}: L D L^T {t_ldl * 1e3:.3f} ms, SuperLU {t_slu * 1e3:.3f} ms, "
                  f"ratio {t_ldl / t_slu:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
