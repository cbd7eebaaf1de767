"""6 x 6 rigid-body mass matrices about a body-fixed point, in body axes (SI: kg, kg m,
kg m^2), for a ship and the structures that ride on it (docs/ship.md).

A body's velocity is ``nu = (v, w)``: the velocity of its reference point and its angular
velocity, body axes; its kinetic energy is ``nu . M nu / 2`` and its momenta ``M nu`` (linear
momentum, angular momentum about the reference point). A point mass ``m`` at ``r`` from the
reference point adds::

    [[ m I,     -m [r]x     ],        [r]x y = r x y
     [ m [r]x,  -m [r]x [r]x ]]

A lumped finite-element node adds this one component at a time: the component ``k`` of its
velocity is ``T_k . nu`` with ``T_k = (e_k, r x e_k)``, so each component it has adds ``m T_k
T_k^T`` (:func:`dof_inertia`); all three make the point mass. A node held in only some
components (a roller) so adds only those, and a sum of components is a 6 x 6 mass matrix even
where it is not a point mass's.
"""

from __future__ import annotations

import numpy as np


def ship_inertia(mass: float, inertia) -> np.ndarray:
    """(6, 6) ``diag(m, m, m, I_x, I_y, I_z)`` (kg, kg m^2): a body about its centre of gravity,
    its body axes principal."""
    return np.diag(np.concatenate([np.full(3, float(mass)), np.asarray(inertia, np.float64)]))


def dof_inertia(r: np.ndarray, mass: np.ndarray, components: np.ndarray) -> np.ndarray:
    """(6, 6) mass matrix of the components ``components`` of lumped nodes, about the point
    from which ``r`` is measured (module docstring).

    Parameters
    ----------
    r
        (N, 3) node positions from the reference point, body axes (m).
    mass
        (N,) lumped nodal masses (kg).
    components
        (N, 3) bool: which velocity components of each node count.
    """
    r = np.asarray(r, dtype=np.float64).reshape(-1, 3)
    mu = np.asarray(mass, dtype=np.float64)[:, None] * np.asarray(components, dtype=np.float64)
    x = np.zeros((len(r), 3, 3))                       # [r]x of every node
    x[:, 0, 1], x[:, 0, 2], x[:, 1, 2] = -r[:, 2], r[:, 1], -r[:, 0]
    x[:, 1, 0], x[:, 2, 0], x[:, 2, 1] = r[:, 2], -r[:, 1], r[:, 0]
    out = np.zeros((6, 6))
    out[:3, :3] = np.diag(mu.sum(axis=0))
    out[3:, :3] = np.einsum("nik,nk->ik", x, mu)       # sum of [r]x D
    out[:3, 3:] = out[3:, :3].T
    out[3:, 3:] = np.einsum("nik,nk,njk->ij", x, mu, x)  # sum of [r]x D [r]x^T
    return out


def least_eigenvalue(matrix: np.ndarray, scale: np.ndarray) -> float:
    """The least eigenvalue of ``matrix`` (6, 6) made dimensionless by the positive diagonal
    ``scale`` (6,): of ``D M D`` with ``D = scale^-1/2`` (0 for a matrix that is only positive
    semi-definite, negative for one that is not even that)."""
    d = 1.0 / np.sqrt(np.asarray(scale, dtype=np.float64))
    return float(np.linalg.eigvalsh(d[:, None] * (0.5 * (matrix + matrix.T)) * d[None, :])[0])


def point_of(matrix: np.ndarray) -> tuple[float, np.ndarray]:
    """The mass (kg) of a 6 x 6 mass matrix and the centre of that mass (m) from its reference
    point, from its translation block's trace and its first moment (0 for no mass)."""
    m = float(np.trace(matrix[:3, :3]) / 3.0)
    s = np.array([matrix[5, 1], matrix[3, 2], matrix[4, 0]])   # m [r]x below the diagonal
    return m, (s / m if m > 0.0 else np.zeros(3))
