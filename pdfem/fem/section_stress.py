"""Nominal (beam-theory) stress at a section of a structure, from the section's resultants.

The cantilever-beam method of propeller blade strength treats the blade outboard of a section
as a cantilever: the normal stress over the section is the axial force over the area plus the
bending moments about the section's principal axes over the second moments, linear across the
section: the flexure formula of beam theory for unsymmetric bending (checked here against
the rectangle's ``6 F L / (b h^2)``, tests/fem/test_section_stress.py). For propellers it is
Taylor's method (Carlton, "The strength of
marine propeller blades", Lloyd's Register Technical Association, paper 2, 1980-81; Morgan,
"An approximate method of obtaining stress in a propeller blade", David Taylor Model Basin
report 919, 1954; of both only the title pages and summaries could be reached here, so no
acceptance rests on them). It is the kind of stress the
rules' blade strength checks give (a bending moment over a section modulus at the root section;
the ice-class rule's formula could not be checked against its text here, docs/propeller.md),
and, unlike the elastic stress at the
junction of a blade with a rigid hub (singular at the clamped edge), it converges under mesh
refinement: it needs only the resultants, which equilibrium fixes, and the section's geometry.

Here the section is a surface group of the mesh (a blade's root face, clamped to the hub),
projected onto the plane normal to the blade's spindle: section axes ``n`` (the spindle,
outboard), ``e1``, ``e2`` (right-handed, ``e1 x e2 = n``), section coordinates
``eta = ((x - c) . e1, (x - c) . e2)`` about the projected area's centroid ``c``. Projected,
because the resultant force along the spindle of a normal stress on a curved face (the hub
cylinder) is the stress times the projected area. Section properties (:func:`section_of`) are
exact integrals over the face's triangles (the linear triangles through all FE nodes,
:meth:`pdfem.fem.fe_space.FESpace.face_triangles`). The resultants (:func:`resultants`) are
those the part outboard of the section puts on the support: with the supports' nodal forces
``R`` on the structure (frame axes), ``F = -sum R`` and ``M = -sum (x - c) x R`` about ``c``.
The normal stress (:func:`nominal_stress`, tension positive) is

    sigma(eta) = F_n / A + b . eta,    I b = (-M_2, M_1),    I = [[I_11, I_12], [I_12, I_22]]

(``M_1``, ``M_2`` the moment's components along ``e1``, ``e2``; ``I_ij = int eta_i eta_j dA``),
the unsymmetric-bending form of ``sigma = F_n / A + M_xi zeta / I_xi - M_zeta xi / I_zeta`` in
the principal axes (:func:`principal_axes`), read at the section's nodes; its largest value is
the nominal root stress in tension, its smallest the one in compression. Shear from the
transverse force and the spindle torque is not part of it (nor of the method).

SI units: m, m^2, m^4, N, N m, Pa.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pdfem.geometry.vectors import cross

_EDGE_MIDPOINTS = np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]])
"""Barycentric weights of a triangle's edge midpoints: the three-point rule exact for
quadratics (the second moments)."""


@dataclass(frozen=True)
class Section:
    """A section's geometry in its plane (see the module docstring).

    Attributes
    ----------
    centroid
        (3,) m, centroid ``c`` of the projected area, in the coordinates of the points given.
    axes
        (3, 3) rows ``n`` (normal, outboard), ``e1``, ``e2``: right-handed unit vectors.
    area
        Projected area ``A`` (m^2).
    inertia
        (2, 2) second moments of area ``I_ij = int eta_i eta_j dA`` about ``c`` (m^4).
    fibres
        (P, 2) section coordinates ``eta`` (m) of the section's nodes, where the stress is read.
    flexibility
        (2, 2) the inverse of ``inertia`` (1/m^4).
    """

    centroid: np.ndarray
    axes: np.ndarray
    area: float
    inertia: np.ndarray
    fibres: np.ndarray
    flexibility: np.ndarray


def section_axes(normal, first) -> np.ndarray:
    """(3, 3) rows ``n``, ``e1``, ``e2`` of a section normal to ``normal``: ``e1`` is ``first``
    made normal to ``n``, ``e2 = n x e1``."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    e1 = np.asarray(first, dtype=np.float64)
    e1 = e1 - (e1 @ n) * n
    e1 = e1 / np.linalg.norm(e1)
    return np.array([n, e1, cross(n, e1)])


def section_of(points: np.ndarray, triangles: np.ndarray, axes: np.ndarray) -> Section:
    """The section of the face ``triangles`` projected onto the plane normal to ``axes[0]``.

    Parameters
    ----------
    points
        (N, 3) node coordinates (m).
    triangles
        (T, 3) node indices of the face's linear triangles (any orientation; a face that
        folds over itself in projection is not a section).
    axes
        (3, 3) rows ``n``, ``e1``, ``e2`` (:func:`section_axes`).

    Returns
    -------
    Section
        Centroid, axes, projected area, second moments about the centroid and the coordinates
        of the nodes of ``triangles``.

    Raises
    ------
    ValueError
        If the face has no projected area.
    """
    axes = np.asarray(axes, dtype=np.float64)
    p = np.asarray(points, dtype=np.float64)
    tri = np.asarray(triangles, dtype=np.int64)
    q = p[tri] @ axes[1:].T                                       # (T, 3, 2) in-plane coordinates
    d1, d2 = q[:, 1] - q[:, 0], q[:, 2] - q[:, 0]
    a = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])   # (T,) projected areas
    area = float(a.sum())
    if not area > 0.0:
        raise ValueError("the section has no area in the plane normal to its axis")
    mid = np.einsum("mk,tkj->tmj", _EDGE_MIDPOINTS, q)            # (T, 3, 2)
    first = np.einsum("t,tmj->j", a / 3.0, mid)
    c2 = first / area
    eta = mid - c2
    inertia = np.einsum("t,tmi,tmj->ij", a / 3.0, eta, eta)
    # the centroid in 3-D: in the plane through the area-weighted mean of the points along n
    depth = float(np.einsum("t,tk->", a / 3.0, p[tri] @ axes[0])) / area
    centroid = depth * axes[0] + c2[0] * axes[1] + c2[1] * axes[2]
    nodes = np.unique(tri)
    return Section(centroid, axes, area, inertia, p[nodes] @ axes[1:].T - c2,
                   np.linalg.inv(inertia))


def principal_axes(section: Section) -> tuple[np.ndarray, np.ndarray]:
    """The principal second moments of area (m^4, ascending) of ``section`` and the axes
    (rows: unit ``(e1, e2)`` components) about which they are taken: the smallest about the
    section's long direction (a blade section's chord)."""
    values, vectors = np.linalg.eigh(section.inertia)   # vectors: the directions of spread
    return values, np.column_stack([-vectors[1], vectors[0]])


def resultants(section: Section, positions: np.ndarray,
               forces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The force (N) and the moment about the centroid (N m) that the part beyond the section
    puts on the supports holding it, in section axes ``(n, e1, e2)``.

    Parameters
    ----------
    section
        The section (:func:`section_of`).
    positions
        (H, 3) positions (m) of the held nodes, in the section's coordinates.
    forces
        (H, 3) forces (N) of the supports on those nodes, same axes.
    """
    r = np.asarray(forces, dtype=np.float64)
    force = -r.sum(axis=0)
    moment = -cross(np.asarray(positions, dtype=np.float64) - section.centroid, r).sum(axis=0)
    return section.axes @ force, section.axes @ moment


def nominal_stress(section: Section, force: np.ndarray, moment: np.ndarray) -> np.ndarray:
    """(P,) normal stress (Pa, tension positive) at the section's nodes from its resultants
    (section axes, :func:`resultants`): ``F_n / A + b . eta`` with ``I b = (-M_2, M_1)``."""
    b = section.flexibility @ np.array([-moment[2], moment[1]])
    return force[0] / section.area + section.fibres @ b


def stress_range(section: Section, force: np.ndarray, moment: np.ndarray
                 ) -> tuple[float, float, float]:
    """The largest and the smallest normal stress over the section and the axial part
    ``F_n / A`` (Pa) of the resultants ``force`` (N) and ``moment`` (N m, about the centroid),
    section axes (:func:`nominal_stress`)."""
    sigma = nominal_stress(section, force, moment)
    return float(sigma.max()), float(sigma.min()), float(force[0] / section.area)
