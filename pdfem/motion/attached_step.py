"""A ship with the structures riding on it as one mechanical system: whether the inertia the
case gives the ship leaves the rigid hull a body, and the stable step of the whole (SI: kg,
kg m^2, N/m, 1/s^2; docs/ship.md).

The ship's ``mass``, ``center_of_gravity`` and ``radii_of_gyration`` are the whole ship's, the
structures attached to it included. The rigid hull alone is what is left: its 6 x 6 mass
matrix about G is the whole ship's less the riders' (every degree of freedom of every rider,
:func:`pdfem.motion.rigid_inertia.dof_inertia`), and it must be a mass matrix, positive
semi-definite (:func:`hull_inertia_problem`): a hull's mass and rotational inertia about its own
centre of gravity are not negative. At 100 % (the riders carry the whole ship's mass) the hull
is a massless shell that floats them; then their centre of gravity must be the ship's and their
inertia at most the ship's.

The ship integrates the hull with the riders' supported degrees of freedom as one rigid body
(:mod:`pdfem.motion.ship`), and each rider's free degrees of freedom are ordinary lumped
masses tied to it by the rider's stiffness. Written in world displacements the system's mass
matrix is block diagonal, the body's 6 x 6 and the free masses, and its stiffness is the
riders' ``K`` on ``d = (x_free, T_held xi)`` (``xi`` the body's small rigid displacement,
``T`` the rigid motion of a degree of freedom, ``K T = 0``) plus the water's spring on ``xi``.
Central differences on it are stable for steps below ``2 / omega_max``, ``omega_max^2`` the
largest eigenvalue of that pair (:func:`assembly_max_eigenvalue`, by the power iteration of
:func:`pdfem.fem.explicit.power_iteration_max_eigenvalue`): at least the rider's own with its
supports held still, and close to it when the hull is much heavier than the rider's support
nodes.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from pdfem.fem.explicit import power_iteration_max_eigenvalue
from pdfem.motion.rigid_inertia import least_eigenvalue, point_of

TOLERANCE = 1e-9
"""Least eigenvalue (relative to the whole ship's diagonal) of the hull's own mass matrix that
still counts as positive semi-definite: round-off of a rider that carries exactly the ship's
mass at its centre of gravity (at 100 % a rider whose centre is a length ``d`` from G leaves
about ``-(d / k)^2``, ``k`` the radius of gyration)."""


def hull_inertia_problem(ship, riders: list, parts: list) -> tuple[str, str] | None:
    """What is wrong with the rigid hull that ``riders`` leave of ``ship``, or None.

    Parameters
    ----------
    ship
        The :class:`pdfem.motion.ship.Ship` (``total_inertia``, ``mass``, ``name``).
    riders
        The structures riding on it (their ``name``).
    parts
        Per rider, its 6 x 6 mass matrices about G in body axes: all its degrees of freedom,
        its free ones.

    Returns
    -------
    tuple or None
        ``(key, message)``: the ship's input that is too small (``"mass"`` or
        ``"radii_of_gyration"``) and what is wrong, in words.
    """
    total = ship.total_inertia
    attached = sum(a for a, _ in parts)
    mass, centre = point_of(attached)
    names = ", ".join(repr(r.name) for r in riders)
    whole = ("the ship's mass, centre of gravity and radii of gyration are those of the whole "
             "ship, the structures attached to it included, so the rigid hull alone is what "
             "they leave (docs/ship.md)")
    if mass > ship.mass * (1.0 + TOLERANCE):
        return "mass", (f"the structures riding on ship '{ship.name}' ({names}) weigh "
                        f"{mass:.6g} kg, more than the whole ship's {ship.mass:.6g} kg; {whole}: "
                        "give the ship a mass at least theirs (ship.mass; the default is the "
                        "hull's displaced mass), or lighter structures (their material.density)")
    if least_eigenvalue(total - attached, np.diag(total)) < -TOLERANCE:
        return "radii_of_gyration", (
            f"the structures riding on ship '{ship.name}' ({names}: {mass:.6g} kg of the "
            f"ship's {ship.mass:.6g} kg, their centre of gravity "
            f"{np.array2string(centre, precision=4)} m from the ship's) carry more inertia "
            f"about the ship's centre of gravity than the ship's radii of gyration "
            f"{np.array2string(np.sqrt(ship.inertia / ship.mass), precision=4)} m give the "
            f"whole ship; {whole}, whose mass and rotational inertia about its own centre of "
            "gravity cannot be negative (a rider with all the ship's mass must be centred on "
            "the ship's centre of gravity): give larger ship.radii_of_gyration, a "
            "ship.center_of_gravity nearer the riders, or lighter structures")
    body = total - sum(f for _, f in parts)
    if least_eigenvalue(body, np.diag(total)) <= TOLERANCE:
        return "radii_of_gyration", (
            f"the hull of ship '{ship.name}' keeps no inertia of its own about some axis and "
            f"the supports of its riders ({names}) lie on a line: the hull cannot turn about "
            "it; give the ship some inertia of its own (ship.mass, ship.radii_of_gyration) or "
            "support the structures at points off one line")
    return None


def rigid_rows(points: np.ndarray, dofs: np.ndarray) -> np.ndarray:
    """(n, 6) ``T``: row ``dofs[c, k]`` is ``(e_c, r_k x e_c)``, the displacement of component
    ``c`` of the node at ``points[k]`` (m, from the body's reference point) under a rigid
    displacement and small rotation ``(dx, dtheta)`` of the body."""
    n = int(dofs.max()) + 1
    out = np.zeros((n, 6))
    for c in range(3):
        e = np.zeros(3)
        e[c] = 1.0
        out[dofs[c], c] = 1.0
        out[dofs[c], 3:] = np.cross(points, e)
    return out


def assembly_max_eigenvalue(body: np.ndarray, water: np.ndarray, riders: list,
                            point: np.ndarray) -> float:
    """``omega_max^2`` (1/s^2) of a ship's integrated body with its riders' free degrees of
    freedom (module docstring).

    Parameters
    ----------
    body
        (6, 6) the body's mass matrix about ``point``, body axes (positive definite).
    water
        (6, 6) the water's stiffness on the body's rigid motions
        (:func:`pdfem.motion.hydrostatics.restoring_stiffness`).
    riders
        The structures riding on it: ``coupling_parts(point)`` gives a rider's ``K`` (sparse),
        its free-DOF mask, its lumped masses and its rows ``T`` (:func:`rigid_rows`).
    point
        (3,) the body's reference point in the mesh (m).
    """
    lower_inv = np.linalg.inv(np.linalg.cholesky(body))   # body = L L^T, coordinates L^T xi
    rows, border, corner = [], [], lower_inv @ water @ lower_inv.T
    for r in riders:
        K, free, mass, T = r.coupling_parts(point)
        K = sp.csr_matrix(K)
        d = 1.0 / np.sqrt(mass[free])
        th = T[~free]
        kf = K[free]
        rows.append(sp.diags(d) @ kf[:, free] @ sp.diags(d))
        border.append(d[:, None] * (kf[:, ~free] @ th) @ lower_inv.T)
        corner = corner + lower_inv @ (th.T @ (K[~free][:, ~free] @ th)) @ lower_inv.T
    n = len(rows)
    blocks = [[rows[i] if i == j else None for j in range(n)] + [sp.csr_matrix(border[i])]
              for i in range(n)]
    blocks.append([sp.csr_matrix(b.T) for b in border] + [sp.csr_matrix(corner)])
    a = sp.bmat(blocks, format="csr")
    a = 0.5 * (a + a.T)
    return power_iteration_max_eigenvalue(a, np.ones(a.shape[0]))[0]
