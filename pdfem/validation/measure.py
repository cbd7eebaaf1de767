"""Signal measurements shared by the validation cases: crossings, spectral peaks, momenta.

Plain functions of numpy arrays in SI units; each validation case combines them with the
arrays of its run's results (:func:`pdfem.output.read_results`).
"""

from __future__ import annotations

import numpy as np


def zero_crossings(time: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Times (s) where ``values`` changes sign, linearly interpolated between samples.

    Samples that are exactly zero at the start (a signal starting from rest) are skipped.
    """
    t = np.asarray(time, dtype=np.float64)
    w = np.asarray(values, dtype=np.float64)
    start = int(np.argmax(w != 0.0)) if np.any(w != 0.0) else len(w)
    t, w = t[start:], w[start:]
    i = np.flatnonzero(np.sign(w[:-1]) * np.sign(w[1:]) < 0)
    return t[i] - w[i] * (t[i + 1] - t[i]) / (w[i + 1] - w[i])


def windowed_spectrum(time: np.ndarray, values: np.ndarray,
                      padding: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """Frequencies (Hz) and magnitudes of the spectrum of a uniformly sampled signal: the mean
    removed, a Hann window applied, the FFT zero-padded to ``padding`` times the length."""
    t = np.asarray(time, dtype=np.float64)
    w = np.asarray(values, dtype=np.float64)
    dt = (t[-1] - t[0]) / (len(t) - 1)
    n_fft = padding * len(w)
    return (np.fft.rfftfreq(n_fft, dt),
            np.abs(np.fft.rfft((w - w.mean()) * np.hanning(len(w)), n_fft)))


def spectral_peak(time: np.ndarray, values: np.ndarray, padding: int = 32) -> float:
    """Frequency (Hz) of the largest peak of :func:`windowed_spectrum`, located between bins by
    a parabola through the three largest values."""
    f, spectrum = windowed_spectrum(time, values, padding)
    k = int(np.argmax(spectrum[1:-1])) + 1
    a, b, c = spectrum[k - 1], spectrum[k], spectrum[k + 1]
    return float(f[k] + 0.5 * (a - c) / (a - 2 * b + c) * (f[1] - f[0]))


def ice_momentum(body: dict, density: float, frame: int = -1) -> np.ndarray:
    """Linear momentum (kg m/s, (3,)) of an ice body's frame: ``density * sum(volume * v)``.

    ``body`` is one ``results["ice"][name]`` entry of :func:`pdfem.output.read_results`.
    """
    return density * (body["volume"][:, None] * body["v"][frame]).sum(axis=0)


def cell_volumes(points: np.ndarray, cells: np.ndarray, cell_type: str) -> np.ndarray:
    """Volumes (m^3) of linear tetrahedra, or of axis-aligned box hexahedra (their extents)."""
    p = points[cells]
    if cell_type == "tetra":
        d = p[:, 1:] - p[:, :1]
        return np.abs(np.linalg.det(d)) / 6.0
    if cell_type == "hexahedron":
        return np.prod(p.max(axis=1) - p.min(axis=1), axis=1)
    raise ValueError(f"no volume formula for {cell_type} cells")


def structure_mass_centre(structure: dict, density: float, frame: int) -> tuple[float, np.ndarray]:
    """Mass (kg) and mass-weighted displacement (kg m, (3,)) of an elastic structure's frame.

    ``sum_e rho V_e mean(u of e's nodes)``: the integral of rho u for linear tetrahedra and for
    axis-aligned box hexahedra (each node carries V_e/4 resp. V_e/8 of the element's mass,
    the lumped masses of the FE model). ``structure`` is one ``results["structure"][name]``.
    """
    vol = cell_volumes(structure["points"], structure["cells"], structure["cell_type"])
    u = structure["u"][frame]
    return density * float(vol.sum()), density * (vol[:, None] * u[structure["cells"]].mean(axis=1)).sum(axis=0)


def structure_momentum(structure: dict, time: np.ndarray, density: float) -> np.ndarray:
    """Linear momentum (kg m/s, (3,)) of a structure in free flight over its last two frames.

    With no load on it between the frames, the central difference scheme moves its mass centre
    uniformly, so the momentum is the change of ``sum m u`` over the time between the frames
    (exact to round-off; :func:`structure_mass_centre`).
    """
    _, a = structure_mass_centre(structure, density, -2)
    _, b = structure_mass_centre(structure, density, -1)
    return (b - a) / (time[-1] - time[-2])


def contact_window(force: np.ndarray) -> tuple[int, int]:
    """First and last index (inclusive) of the nonzero entries of a (K,) contact-force history."""
    on = np.flatnonzero(np.asarray(force) != 0.0)
    if len(on) == 0:
        raise ValueError("no contact force at any step")
    return int(on[0]), int(on[-1])
