"""The blocks of a body's pair loops, fixed by the whole body: the same sums on 1 and N ranks.

The pair loops take every particle's sums in an order fixed by the blocks of global particle
numbers they run over (:mod:`pdfem.pd.bonds.workspace`). :func:`layout_workspace` sizes those
blocks from the whole body (its particle and bond counts and the reach of its bonds in the
global numbering, each gathered over the ranks of the layout) and cuts the local part into
them, so a rank's part of a body takes each owned particle's sums exactly as the whole body
does, and no figure depends on the thread count.
"""

from __future__ import annotations

import numpy as np

from pdfem.pd.bonds.chunk_kernels import max_reach
from pdfem.pd.bonds.workspace import PairWorkspace, block_bounds


def layout_workspace(row_ptr: np.ndarray, nbr: np.ndarray, layout,
                     keep_bond_length: bool = True) -> PairWorkspace:
    """The :class:`~pdfem.pd.bonds.workspace.PairWorkspace` of a local pair list (rows in the
    layout's global order) on the whole body's blocks (collective)."""
    counted = np.repeat(layout.owned, np.diff(row_ptr)).sum(dtype=np.int64)
    n_pairs = int(layout.allsum(np.int64(counted)))
    reach = max(layout.comm.allgather(int(max_reach(row_ptr, nbr, layout.gid))))
    bounds = block_bounds(layout.n_global, n_pairs, reach)
    return PairWorkspace(row_ptr, nbr, keep_bond_length=keep_bond_length, bounds=bounds,
                         gid=layout.gid)
