"""Input checks for coordinates: 3-vectors and (N, 3) point arrays (m)."""

from __future__ import annotations

import numpy as np


def vec3(value, name: str, what: str) -> tuple[float, float, float]:
    """``value`` as three finite floats; ValueError naming the ``what``'s ``name`` otherwise."""
    arr = np.asarray(value, dtype=np.float64).reshape(-1)
    if arr.shape != (3,):
        raise ValueError(f"the {what}'s {name} must have 3 components, got {arr.shape[0]}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"the {what}'s {name} must be finite, got {arr.tolist()}")
    return (float(arr[0]), float(arr[1]), float(arr[2]))


def as_points(x) -> np.ndarray:
    """``x`` as an (N, 3) float64 array; ValueError otherwise."""
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"points must be an (N, 3) array, got shape {x.shape}")
    return x
