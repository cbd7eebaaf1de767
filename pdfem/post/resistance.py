"""Ice resistance of a ship: the history, its steady phase, mean and standard deviation, and the
resistance plot of ``pdfem post`` (docs/icebreaking.md). SI units: N, s.

The ice resistance is the ice's force on the hull against the ship's heading: ``R = -F . e``
with ``F`` the hull's ice load (``loads/<hull>/force``, every coupling step) and ``e`` the
heading, +x for the hull of ``models/icebreaker.py`` (towed rigid hulls keep their attitude).
Its *steady phase* starts when the bow is fully in the ice. Without a given start this module
takes it at ``t_0 + STEADY_FRACTION (t_end - t_0)``, ``t_0`` the first sample with a load:
the bow's waterline entrance is the first third to half of the run of the icebreaking cases,
so the last 40 % are past it. Mean and standard deviation are time-weighted (trapezoid rule)
over the steady phase. Loads per hull group are the hull's load patches
(:func:`group_resistance`, ``loads/<hull>.<group>``, written every coupling step).
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import numpy as np

from pdfem.post.windowed import windowed_force


STEADY_FRACTION = 0.6
"""Fraction of the loaded span (from the first contact to the end) before the steady phase."""

HULL_MODELS = ("icebreaker",)
"""Mesh models whose structures are ships in the resistance summary (``mesh = "icebreaker"``
or a path ending in ``icebreaker.py``)."""


def hull_names(case_text: str) -> list[str]:
    """Names of the case's structures whose mesh is a ship hull model (:data:`HULL_MODELS`)."""
    try:
        case = tomllib.loads(case_text or "")
    except tomllib.TOMLDecodeError:
        return []
    return [s.get("name", "") for s in case.get("structure", [])
            if Path(str(s.get("mesh", ""))).stem in HULL_MODELS]


def resistance_history(force: np.ndarray, heading=(1.0, 0.0, 0.0)) -> np.ndarray:
    """The ice resistance R = -F . e (N) of each sample of the hull's ice load ``force``
    ((K, 3), N) for the unit heading ``e``."""
    e = np.asarray(heading, dtype=np.float64)
    return -np.asarray(force, dtype=np.float64) @ (e / np.linalg.norm(e))


def steady_start(time: np.ndarray, resistance: np.ndarray) -> float:
    """Default start of the steady phase (s): ``t_0 + STEADY_FRACTION (t_end - t_0)``,
    ``t_0`` the first sample with a non-zero resistance (the end time if there is none)."""
    loaded = np.flatnonzero(resistance != 0.0)
    t0 = float(time[loaded[0]]) if loaded.size else float(time[-1])
    return t0 + STEADY_FRACTION * (float(time[-1]) - t0)


def steady_figures(time: np.ndarray, resistance: np.ndarray,
                   start: float | None = None) -> dict[str, Any]:
    """Mean and standard deviation of the resistance over its steady phase.

    Parameters
    ----------
    time
        (K,) sample times, s, increasing.
    resistance
        (K,) ice resistance, N (:func:`resistance_history`).
    start
        Start of the steady phase, s; default :func:`steady_start`.

    Returns
    -------
    dict
        ``start``, ``end`` (s), ``samples``, ``mean``, ``std`` and ``peak`` (N) over
        ``time >= start`` (time-weighted by the trapezoid rule; a single sample is its own
        mean, std 0); ``std`` and ``peak`` of the resistance averaged over ``window`` (s,
        :func:`pdfem.post.windowed.windowed_force`: step independent; the mean is the raw
        history's);
        ``per_step_peak`` (N) the step-dependent peak of the raw per-step resistance; NaN
        figures when no sample is in the phase.
    """
    t = np.asarray(time, dtype=np.float64)
    r = np.asarray(resistance, dtype=np.float64)
    t_start = steady_start(t, r) if start is None else float(start)
    m = t >= t_start
    out: dict[str, Any] = {"start": t_start, "end": float(t[-1]) if t.size else float("nan"),
                           "samples": int(m.sum())}
    if not m.any():
        return out | {"mean": float("nan"), "std": float("nan"), "peak": float("nan"),
                      "per_step_peak": float("nan"), "window": float("nan")}
    tw, rw, window = windowed_force(t, r)
    keep = tw >= t_start
    mean, _ = _weighted(t[m], r[m], None)
    _, var = _weighted(tw[keep], rw[keep], mean) if keep.any() else _weighted(t[m], r[m], mean)
    peak = float(rw[keep].max()) if keep.any() else float(r[m].max())
    return out | {"mean": mean, "std": var ** 0.5, "peak": peak,
                  "per_step_peak": float(r[m].max()), "window": window}


def _weighted(t: np.ndarray, y: np.ndarray, mean: float | None) -> tuple[float, float]:
    """Time-weighted (trapezoid) mean of ``y`` and its variance about ``mean`` (default: that
    mean); a single sample or no span: the plain mean and variance."""
    if t.size == 1 or t[-1] <= t[0]:
        m = float(y.mean()) if mean is None else mean
        return m, float(np.mean((y - m) ** 2))
    span = t[-1] - t[0]
    m = float(np.trapezoid(y, t) / span) if mean is None else mean
    return m, float(np.trapezoid((y - m) ** 2, t) / span)


def resistance_summary(results: dict) -> dict[str, dict]:
    """``{hull: steady figures}`` (:func:`steady_figures`, N and s, and ``groups``: the
    :func:`group_resistance` of the steady phase) of every ship hull of the case stored in the
    results (:func:`hull_names`) that has a load history."""
    hist = results["histories"]
    out = {}
    for name in hull_names(results.get("meta", {}).get("case", "")):
        h = hist.get(f"loads/{name}")
        if h is not None and h["time"].size:
            out[name] = steady_figures(h["time"], resistance_history(h["force"]))
            out[name]["groups"] = group_resistance(results, name, out[name]["start"])
    return out


def group_resistance(results: dict, name: str, start: float) -> dict[str, dict]:
    """Per load patch of hull ``name`` (its mesh's surface groups on the contact surface: bow,
    shoulder, midship, stern, bow_panel of ``models/icebreaker.py``; history
    ``loads/<name>.<group>``), the time-weighted mean ice force (N, normal and friction) and
    its resistance part ``-F_x`` (N) over the samples from ``start`` (s). Empty without
    patches or samples after ``start``."""
    out = {}
    prefix = f"loads/{name}."
    for key, h in sorted(results["histories"].items()):
        if not key.startswith(prefix):
            continue
        t, f = h["time"], h["force"]
        keep = t >= start
        if np.count_nonzero(keep) < 2:
            continue
        ts, fs = t[keep], f[keep]
        mean = np.trapezoid(fs, ts, axis=0) / (ts[-1] - ts[0])
        out[key[len(prefix):]] = {"force": mean.tolist(), "resistance": float(-mean[0])}
    return out


def plot_resistance(results: dict, path: Path, written: list[Path]) -> None:
    """``resistance.png``: each hull's ice resistance against time, its steady-phase mean
    (line) and mean +- one standard deviation (band); nothing without a ship hull."""
    figures = resistance_summary(results)
    if not figures:
        return
    from matplotlib.figure import Figure  # no pyplot: no global figure state, Agg canvas
    fig = Figure(figsize=(8.0, 3.2 * len(figures) + 0.6), layout="constrained")
    axes = fig.subplots(len(figures), 1, squeeze=False)
    for ax, (name, f) in zip(axes[:, 0], figures.items()):
        h = results["histories"][f"loads/{name}"]
        ax.plot(h["time"], resistance_history(h["force"]), lw=0.6, label="ice resistance -F_x")
        span = (f["start"], f["end"])
        ax.fill_between(span, f["mean"] - f["std"], f["mean"] + f["std"], color="C1", alpha=0.3,
                        label=f"steady phase: mean +- std ({f['std']:.3g} N)")
        ax.plot(span, (f["mean"], f["mean"]), color="C1", label=f"mean {f['mean']:.3g} N")
        ax.set_title(f"Ice resistance of '{name}'")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("resistance [N]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.savefig(path, dpi=150, format="png")
    written.append(path)
