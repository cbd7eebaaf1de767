"""Peridynamic particles on a cubic lattice filling a shape.

Each particle represents a cube of side ``dx`` (m) centred on it, so its volume is ``dx**3``
(m^3). The lattice is anchored at the minimum corner of the shape's bounding box ``lo`` and is
cell-centred: points ``lo + (i + 0.5) dx`` for ``i = 0 .. n_k - 1`` along each axis ``k``, with
``n_k = max(1, round((hi_k - lo_k) / dx))``. A box whose sides are multiples of ``dx`` is thus filled
exactly, every particle owning its own dx^3 of the box. For curved shapes the points whose
centre lies inside the shape are kept, so the body's volume is right up to the discretisation of
its surface (the particle count times dx^3 converges to the shape's volume as dx -> 0).

No volume correction is applied here: the partial-volume correction for neighbours that straddle
the edge of the horizon is applied by the bond kernels (:mod:`pdfem.pd.bonds.kernels`).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["fill", "lattice_axes", "lattice_plane", "lattice_points", "particle_volume"]


def lattice_points(lo: np.ndarray, hi: np.ndarray, dx: float) -> np.ndarray:
    """Cell-centred cubic lattice of spacing ``dx`` covering the box ``[lo, hi]``.

    Parameters
    ----------
    lo, hi
        (3,) corners of the box, m.
    dx
        Lattice spacing, m (> 0).

    Returns
    -------
    ndarray
        (n_x n_y n_z, 3) float64 points ``lo + (i + 0.5) dx``, in x-major / y / z loop order
        (z varies fastest).
    """
    dx = _check_dx(dx)
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    counts = [max(1, int(round((hi[k] - lo[k]) / dx))) for k in range(3)]
    axes = [lo[k] + (np.arange(counts[k], dtype=np.float64) + 0.5) * dx for k in range(3)]
    out = np.empty((counts[0], counts[1], counts[2], 3), dtype=np.float64)
    out[..., 0] = axes[0][:, None, None]
    out[..., 1] = axes[1][None, :, None]
    out[..., 2] = axes[2][None, None, :]
    return out.reshape(-1, 3)


def fill(shape, dx: float) -> np.ndarray:
    """Points of a cubic lattice of spacing ``dx`` that lie inside ``shape``.

    Parameters
    ----------
    shape
        A :mod:`pdfem.geometry.shapes` object (``bounds()``, ``contains(x)``, ``fills_bounds``).
    dx
        Lattice spacing, m (> 0).

    Returns
    -------
    ndarray
        (N,3) float64 particle positions, m, in x-major / y / z loop order. For a shape
        that fills its bounds (a :class:`~pdfem.geometry.shapes.Box`) every lattice point of the
        box is kept; for other shapes the points where ``shape.contains`` is true.
    """
    dx = _check_dx(dx)
    lo, hi = shape.bounds()
    pts = lattice_points(lo, hi, dx)
    if shape.fills_bounds:
        return pts
    return np.ascontiguousarray(pts[shape.contains(pts)])


def particle_volume(dx: float) -> float:
    """Volume (m^3) of one lattice particle of spacing ``dx`` (m): ``dx**3``."""
    dx = _check_dx(dx)
    return dx ** 3


def _check_dx(dx: float) -> float:
    dx = float(dx)
    if not (math.isfinite(dx) and dx > 0.0):
        raise ValueError(f"the lattice spacing dx must be a positive length in m, got {dx!r}")
    return dx


def lattice_axes(lo: np.ndarray, hi: np.ndarray, dx: float) -> list[np.ndarray]:
    """The coordinates (m) of the lattice planes of :func:`lattice_points` along x, y and z.

    ``lattice_points(lo, hi, dx)[(i * n_y + j) * n_z + k]`` is ``(ax[0][i], ax[1][j], ax[2][k])``
    bit for bit (the same expression per axis), so any block of the lattice can be generated
    from index ranges without the whole array (:func:`lattice_plane`).
    """
    dx = _check_dx(dx)
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    counts = [max(1, int(round((hi[k] - lo[k]) / dx))) for k in range(3)]
    return [lo[k] + (np.arange(counts[k], dtype=np.float64) + 0.5) * dx for k in range(3)]


def lattice_plane(axes: list[np.ndarray], i: int, j: tuple[int, int] | None = None,
                  k: tuple[int, int] | None = None) -> np.ndarray:
    """The points (m) of the lattice plane ``i`` (x index), rows ``j0:j1``, columns ``k0:k1``
    (default: all), in y-major / z order as :func:`lattice_points` lists them."""
    j0, j1 = (0, len(axes[1])) if j is None else j
    k0, k1 = (0, len(axes[2])) if k is None else k
    out = np.empty((j1 - j0, k1 - k0, 3), dtype=np.float64)
    out[..., 0] = axes[0][i]
    out[..., 1] = axes[1][j0:j1, None]
    out[..., 2] = axes[2][None, k0:k1]
    return out.reshape(-1, 3)
