"""Mesh convergence of the hull panel's first natural frequencies (Hz), for choosing its
default ``element_size``.

The panel of ``models/hull_panel.py`` (default geometry: 2.0 m x 1.2 m, 12 mm plating, two
flat-bar stiffeners, one frame; steel E = 210 GPa, nu = 0.3, rho = 7850 kg/m^3; SI units) is
meshed with its default structured hexahedra at each ``element_size``, the elements raised to
20-node serendipity hexahedra (scikit-fem ``ElementHexS2``, as the structure solver does on
load), clamped on the group ``fixed`` (every DOF of its faces), and the first K frequencies
come from the consistent-mass eigenproblem by shift-invert Lanczos (``scipy.sparse.linalg.eigsh``).

Run ``python benchmarks/hull_panel_modes.py 0.1 0.05 0.025`` (sizes in m); prints one JSON line
per size with the counts of the gmsh file (first-order nodes and hexahedra), the quadratic DOFs,
the frequencies and the wall time.
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.sparse.linalg import eigsh
from skfem import Basis, BilinearForm, ElementHexS2, ElementVector, asm
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity

from pdfem.fem.mesh import load_mesh
from pdfem.models import hull_panel

E_MOD, NU, RHO = 210e9, 0.3, 7850.0


def panel_frequencies(element_size: float, layers: int = 1, k: int = 5, folder: str | None = None) -> dict:
    """First ``k`` natural frequencies (Hz) of the clamped default panel at one element size (m).

    Parameters
    ----------
    element_size
        The model's ``element_size``, m.
    layers
        Hexahedra through each thickness.
    k
        Number of frequencies.
    folder
        Where to write the mesh (a temporary folder by default).

    Returns
    -------
    dict
        ``h``, ``layers``, ``nodes``, ``hexes`` (of the first-order file), ``dofs`` (quadratic),
        ``freqs`` (Hz, ascending), ``seconds``.
    """
    t0 = time.time()
    folder = folder or tempfile.mkdtemp()
    report = hull_panel.build(Path(folder) / f"panel_{element_size}_{layers}.msh", element_size=element_size,
                              layers=layers)
    fm = load_mesh(report.path)
    basis = Basis(fm.mesh, ElementVector(ElementHexS2()), intorder=4)
    K = asm(linear_elasticity(*lame_parameters(E_MOD, NU)), basis)
    M = asm(BilinearForm(lambda u, v, w: RHO * dot(u, v)), basis)
    fixed = np.unique(np.concatenate([basis.get_dofs(fm.facet_indices["fixed"]).all(),
                                      basis.nodal_dofs[:, fm.node_sets["fixed"]].ravel()]))
    free = np.setdiff1d(np.arange(basis.N), fixed)
    w2, _ = eigsh(K[free][:, free].tocsc(), k=k, M=M[free][:, free].tocsc(), sigma=0.0, which="LM")
    freqs = np.sqrt(np.abs(np.sort(w2))) / (2 * np.pi)
    return dict(h=element_size, layers=layers, nodes=report.nodes, hexes=report.elements["hexahedron"],
                dofs=int(basis.N), freqs=[round(float(f), 2) for f in freqs], seconds=round(time.time() - t0, 1))


if __name__ == "__main__":
    for size in (float(a) for a in sys.argv[1:]):
        print(json.dumps(panel_frequencies(size)), flush=True)
