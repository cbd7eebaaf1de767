"""Ship motions in ``pdfem post``: the six degrees of freedom of every free hull (``kind =
"ship"``, docs/ship.md) against time, from its history ``motions/<name>`` (every coupling
step). SI units: m, s; angles shown in degrees.

The translation is the centre of gravity's displacement from its position at the first sample
(surge x, sway y, heave z, m); the attitude is the rotation vector's components (axis times
angle), which for the small angles of a ship in ice are roll, pitch and yaw about the world x,
y and z axes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

PREFIX = "motions/"
"""History groups of free hulls: ``motions/<name>``."""


def ship_motions(results: dict) -> dict[str, dict]:
    """``{ship name: its motion history}`` of a results file (:func:`pdfem.post.load.
    load_results`) that have samples."""
    return {k[len(PREFIX):]: h for k, h in sorted(results["histories"].items())
            if k.startswith(PREFIX) and h["time"].size}


def motion_figures(h: dict) -> dict[str, list[float]]:
    """Largest excursions of one ship's motion history: ``translation`` (3,) m, the largest
    |displacement| of the centre of gravity from its first position per axis, and ``rotation``
    (3,) deg, the largest |rotation vector component| (roll, pitch, yaw)."""
    d = np.asarray(h["position"]) - np.asarray(h["position"])[0]
    r = np.degrees(np.asarray(h["rotation"]))
    return {"translation": np.abs(d).max(axis=0).tolist(),
            "rotation": np.abs(r).max(axis=0).tolist()}


def plot_motions(results: dict, path: Path, written: list[Path]) -> None:
    """``ship_motions.png``: per free hull, surge, sway and heave (m) and roll, pitch and yaw
    (deg) against time; nothing without a free hull."""
    ships = ship_motions(results)
    if not ships:
        return
    from matplotlib.figure import Figure  # no pyplot: no global figure state, Agg canvas
    fig = Figure(figsize=(8.0, 3.0 * 2 * len(ships) + 0.6), layout="constrained")
    axes = fig.subplots(2 * len(ships), 1, squeeze=False)[:, 0]
    for k, (name, h) in enumerate(ships.items()):
        t = h["time"]
        d = np.asarray(h["position"]) - np.asarray(h["position"])[0]
        r = np.degrees(np.asarray(h["rotation"]))
        for i, label in enumerate(("surge x", "sway y", "heave z")):
            axes[2 * k].plot(t, d[:, i], lw=0.8, label=label)
        for i, label in enumerate(("roll (x)", "pitch (y)", "yaw (z)")):
            axes[2 * k + 1].plot(t, r[:, i], lw=0.8, label=label)
        axes[2 * k].set_ylabel("displacement of G [m]")
        axes[2 * k].set_title(f"Motions of ship '{name}'")
        axes[2 * k + 1].set_ylabel("rotation [deg]")
        for ax in axes[2 * k:2 * k + 2]:
            ax.set_xlabel("time [s]")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=8, ncol=3)
    fig.savefig(path, dpi=150)
    written.append(path)
