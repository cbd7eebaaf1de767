"""Zero-phase low-pass filtering of load histories (``pdfem post --lowpass HZ``).

A Butterworth filter of order ``ORDER`` (``scipy.signal.butter``, second-order sections) run
forwards and backwards (``scipy.signal.sosfiltfilt``): no phase shift, so a filtered peak stays
at its time, and the gain is the square of the single pass's,

    |H(f)|^2 = 1 / (1 + (tan(pi f / fs) / tan(pi fc / fs))^(2 N))

(the digital Butterworth filter by the bilinear transform; fs the sampling rate, fc the
cut-off, N the order): 1/2 at the cut-off, whatever N. Ice loads are broad-band: the per-step
history holds single-particle impacts (spikes one step long) over the slower global load; the
filtered history is the global load at frequencies the structure responds to, and the
difference raw - filtered the impacts (fragment hits and crushing events). Units: s, Hz, N.
"""

from __future__ import annotations

import numpy as np

ORDER = 4
"""Order of the Butterworth filter (of one pass)."""


def sampling_rate(time: np.ndarray) -> float:
    """Mean sampling rate (Hz) of equally spaced samples at ``time`` (s)."""
    t = np.asarray(time, dtype=np.float64)
    return (t.size - 1) / (t[-1] - t[0])


def lowpass(time: np.ndarray, values: np.ndarray, cutoff: float,
            order: int = ORDER) -> np.ndarray:
    """Zero-phase Butterworth low-pass of a history (module docstring).

    Parameters
    ----------
    time
        (K,) equally spaced sample times, s.
    values
        (K, ...) samples (filtered along axis 0).
    cutoff
        Cut-off frequency, Hz: > 0 and below the Nyquist frequency fs / 2.
    order
        Order of one pass.

    Returns
    -------
    numpy.ndarray
        The filtered samples, same shape. Histories too short for ``sosfiltfilt``'s padding
        are returned unfiltered.

    Raises
    ------
    ValueError
        If ``cutoff`` is not in (0, fs / 2).
    """
    from scipy.signal import butter, sosfiltfilt

    y = np.asarray(values, dtype=np.float64)
    if len(y) < 2:
        return y.copy()
    fs = sampling_rate(time)
    if not 0.0 < cutoff < fs / 2:
        raise ValueError(f"the cut-off {cutoff:g} Hz must lie between 0 and the Nyquist "
                         f"frequency {fs / 2:g} Hz of the load history (sampled every "
                         f"coupling step, {1 / fs:.3g} s)")
    sos = butter(order, cutoff, btype="low", fs=fs, output="sos")
    pad = 3 * (2 * len(sos) + 1)  # sosfiltfilt's default padding
    if len(y) <= pad:
        return y.copy()
    return sosfiltfilt(sos, y, axis=0)


def gain(frequency: float, cutoff: float, fs: float, order: int = ORDER) -> float:
    """The analytic gain of :func:`lowpass` at ``frequency`` (Hz) (module docstring)."""
    r = np.tan(np.pi * frequency / fs) / np.tan(np.pi * cutoff / fs)
    return float(1.0 / (1.0 + r ** (2 * order)))
