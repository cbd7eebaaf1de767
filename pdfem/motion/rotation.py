"""Rotations of rigid bodies and frames: rotation matrices and unit quaternions.

One home for the rotation arithmetic of :mod:`pdfem.motion`: Rodrigues' formula for a rotation
about an axis (:func:`axis_rotation`, :func:`rotation_matrix`) and the unit quaternions of the
free ship's attitude (Hamilton convention, ``(w, x, y, z)``). Angles in rad.
"""

from __future__ import annotations

import math

import numpy as np

from pdfem.geometry.vectors import cross


def cross_matrix(k: np.ndarray) -> np.ndarray:
    """(3, 3) matrix K with K v = k x v."""
    return np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])


def axis_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """(3, 3) rotation by ``angle`` (rad) about the unit ``axis`` (Rodrigues)."""
    k = cross_matrix(axis)
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def rotation_matrix(rotation_vector) -> np.ndarray:
    """Rotation matrix of a rotation vector (axis times angle in rad), by Rodrigues' formula.

    ``R = I + sin(a) K + (1 - cos(a)) K^2`` with ``a = |r|`` and ``K`` the cross-product matrix
    of the unit axis ``r / a``.
    """
    r = np.asarray(rotation_vector, dtype=np.float64).reshape(3)
    a = float(np.linalg.norm(r))
    if a == 0.0:
        return np.eye(3)
    K = cross_matrix(r / a)
    return np.eye(3) + math.sin(a) * K + (1.0 - math.cos(a)) * (K @ K)


def quaternion_matrix(q: np.ndarray) -> np.ndarray:
    """(3, 3) rotation matrix of a unit quaternion ``(w, x, y, z)``."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def rotation_quaternion(rotation_vector) -> np.ndarray:
    """Unit quaternion of a rotation vector (axis times angle, rad)."""
    r = np.asarray(rotation_vector, dtype=np.float64).reshape(3)
    a = float(np.linalg.norm(r))
    if a == 0.0:
        return np.array([1.0, 0.0, 0.0, 0.0])
    return np.concatenate([[math.cos(a / 2)], math.sin(a / 2) * r / a])


def quaternion_product(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product ``p q`` (the rotation q, then p)."""
    w1, v1, w2, v2 = p[0], p[1:], q[0], q[1:]
    return np.concatenate([[w1 * w2 - v1 @ v2], w1 * v2 + w2 * v1 + cross(v1, v2)])


def rotation_vector(q: np.ndarray) -> np.ndarray:
    """Rotation vector (rad; axis times angle in [0, pi]) of a unit quaternion."""
    q = q if q[0] >= 0 else -q
    s = float(np.linalg.norm(q[1:]))
    if s == 0.0:
        return np.zeros(3)
    return 2.0 * math.atan2(s, q[0]) * q[1:] / s
