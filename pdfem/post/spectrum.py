"""Amplitude spectrum of a sampled signal, e.g. the ice force magnitude on a structure (Hz)."""

from __future__ import annotations

import numpy as np


def amplitude_spectrum(time: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One-sided amplitude spectrum of a sampled signal.

    Parameters
    ----------
    time
        (K,) sample times, s, increasing; meant to be uniform (the coupling step). If the
        spacing varies by more than 1e-6 of the mean step, the signal is first interpolated
        linearly onto K uniform samples over the same span.
    values
        (K,) the signal (e.g. the force magnitude in N).

    Returns
    -------
    frequency : numpy.ndarray
        (K // 2 + 1,) frequencies, Hz, spaced 1 / (K dt).
    amplitude : numpy.ndarray
        Same shape: the amplitude of the cosine at each frequency, in the signal's unit
        (``2 |X_k| / K``; the mean ``|X_0| / K`` at 0 Hz, and ``|X_k| / K`` at the Nyquist
        frequency for even K), so a sine of amplitude A at a bin frequency reads A.
        Empty arrays for fewer than 2 samples.
    """
    t = np.asarray(time, dtype=np.float64)
    y = np.asarray(values, dtype=np.float64)
    k = t.size
    if k < 2 or t[-1] <= t[0]:
        return np.zeros(0), np.zeros(0)
    dt = (t[-1] - t[0]) / (k - 1)
    if np.max(np.abs(np.diff(t) - dt)) > 1e-6 * dt:
        tu = t[0] + dt * np.arange(k)
        y = np.interp(tu, t, y)
    amp = np.abs(np.fft.rfft(y)) / k
    amp[1:] *= 2.0
    if k % 2 == 0:
        amp[-1] /= 2.0
    return np.fft.rfftfreq(k, dt), amp
