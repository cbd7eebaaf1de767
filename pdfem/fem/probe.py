"""Probes: a point of an elastic structure read every coupling step (monitors).

A probe is the node nearest to a point and the element whose centre is nearest; reading it
(:func:`probe_values`) is one small precomputed matrix (the displacement gradient at the
element centre per element DOF) times the element's DOFs, cheap enough for every step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import skfem

from pdfem.fem.stress import hooke_stress, von_mises


@dataclass(frozen=True)
class Probe:
    """A point of a structure read every step: a node and an element (see :func:`make_probe`)."""

    node: int
    element: int
    node_dofs: np.ndarray       # (3,) DOFs of the node
    element_dofs: np.ndarray    # (k,) DOFs of the element
    gradient: np.ndarray        # (9, k) displacement gradient at the element centre per DOF


def make_probe(structure, point) -> Probe:
    """A probe of an :class:`pdfem.fem.structure.ElasticStructure` at ``point`` (m)."""
    s = structure
    point = np.asarray(point, dtype=np.float64).reshape(3)
    node = int(np.argmin(np.linalg.norm(s.node_points - point, axis=1)))
    t = s.mesh.mesh.t
    centres = s.node_points[t].mean(axis=0)  # (Ne, 3)
    element = int(np.argmin(np.linalg.norm(centres - point, axis=1)))
    dofs = s.basis.element_dofs[:, element]
    grad = np.empty((9, len(dofs)))
    sub = skfem.Basis(s.mesh.mesh, s.stress_basis.elem, quadrature=(
        s.stress_basis.X, s.stress_basis.W), elements=np.array([element]))
    for k in range(len(dofs)):
        e = np.zeros(s.dofmap.n_dofs)
        e[dofs[k]] = 1.0
        grad[:, k] = sub.interpolate(e).grad[:, :, 0, 0].ravel()
    return Probe(node, element, s.dofmap.nodal_dofs[:, node].copy(), dofs.copy(), grad)


VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))
"""Index pairs of the six stress components as written: xx, yy, zz, yz, xz, xy."""


def probe_values(structure, probe: Probe) -> tuple[np.ndarray, float, np.ndarray]:
    """Displacement (m, (3,)) of the probe's node, von Mises stress (Pa) of its element and
    its six stress components (Pa, (6,), order of ``VOIGT``: signed, for fatigue counting)."""
    u = structure.solver.u
    sigma = hooke_stress((probe.gradient @ u[probe.element_dofs]).reshape(3, 3), structure.material)
    return (u[probe.node_dofs].copy(), float(von_mises(sigma)),
            np.array([sigma[i, j] for i, j in VOIGT]))
