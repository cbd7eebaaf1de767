"""Report plots of a results file (PNG, matplotlib without a screen).

:func:`write_plots` writes the load history, the load spectrum
(:func:`pdfem.post.spectrum.amplitude_spectrum`), the structural response, an ice damage
snapshot and the energy history of a file read by :func:`pdfem.post.load.load_results`.
SI units on every axis: N, Pa, m, s, Hz, J.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from pdfem.post.groups import AXES, histories_of, patch_loads, split_loads
from pdfem.post.lowpass import lowpass as lowpassed
from pdfem.post.pressure_area import pressure_area
from pdfem.post.motions import plot_motions
from pdfem.post.resistance import plot_resistance
from pdfem.post.shaft import plot_shaft
from pdfem.post.spectrum import amplitude_spectrum
from pdfem.post.windowed import windowed_force


def _figure(rows: int, height: float = 3.0):
    from matplotlib.figure import Figure  # no pyplot: no global figure state, Agg canvas
    fig = Figure(figsize=(8.0, height * rows + 0.6), layout="constrained")
    axes = fig.subplots(rows, 1, squeeze=False)[:, 0]
    return fig, axes


def _save(fig, path: Path, written: list[Path]) -> None:
    fig.savefig(path, dpi=150, format="png")
    written.append(path)


def _finish(ax, title: str, ylabel: str, ncol: int = 1) -> None:
    """Title, axis labels (time on x), grid and legend of a panel of curves over time."""
    ax.set_title(title)
    ax.set_xlabel("time [s]")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize="small", ncol=ncol)


def _plot_loads(loads: dict[str, dict], path: Path, written: list[Path],
                title: str = "Ice force on '{}'", cutoff: float | None = None) -> None:
    fig, axes = _figure(len(loads))
    for ax, (name, h) in zip(axes, loads.items()):
        ax.plot(h["time"], np.linalg.norm(h["force"], axis=1), color="0.75", lw=0.6,
                label="$|F|$ per step (step-dependent)")
        t, f, w = windowed_force(h["time"], h["force"])
        for a, c in enumerate(AXES):
            ax.plot(t, f[:, a], lw=0.9, label=f"$F_{c}$")
        ax.plot(t, np.linalg.norm(f, axis=1), "k", lw=1.2,
                label=f"$|F|$ (solid lines: {w * 1e3:.3g} ms mean)")
        if cutoff is not None:
            f = lowpassed(h["time"], h["force"], cutoff)
            ax.plot(h["time"], np.linalg.norm(f, axis=1), "r", lw=1.5,
                    label=f"$|F|$ low-passed {cutoff:g} Hz")
        _finish(ax, title.format(name), "force [N]")
    _save(fig, path, written)


def _plot_spectrum(loads: dict[str, dict], path: Path, written: list[Path]) -> None:
    fig, axes = _figure(len(loads))
    for ax, (name, h) in zip(axes, loads.items()):
        f, amp = amplitude_spectrum(h["time"], np.linalg.norm(h["force"], axis=1))
        ax.loglog(f[1:], amp[1:], "k", lw=1.0)
        ax.set_title(f"Spectrum of the ice force magnitude on '{name}' "
                     f"(mean {amp[0]:.4g} N not shown)")
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel("amplitude of |F| [N]")
        ax.set_xlim(f[1], f[-1])
        ax.grid(alpha=0.3, which="both")
    _save(fig, path, written)


def _plot_response(results: dict, path: Path, written: list[Path]) -> None:
    t = results["time"]
    hist = results["histories"]
    elastic = {n: s for n, s in sorted(results["structure"].items()) if "von_mises" in s}
    monitors = histories_of(hist, "monitors", "u")
    show_vm = bool(elastic) or any("von_mises" in h for h in monitors.values())
    fig, axes = _figure(2 if show_vm else 1)
    if show_vm:
        ax = axes[0]
        for n, s in elastic.items():
            ax.plot(t, s["von_mises"].max(axis=1), "o-", ms=3, label=f"max over '{n}' (frames)")
        for n, h in monitors.items():
            if "von_mises" in h:
                ax.plot(h["time"], h["von_mises"], lw=0.9, label=f"monitor '{n}'")
        _finish(ax, "Structural response: von Mises stress", "von Mises stress [Pa]")
    ax = axes[-1]
    for n, s in sorted(results["structure"].items()):
        if "contact_pressure" in s:  # a contact surface: its structure is plotted
            continue
        ax.plot(t, np.linalg.norm(s["u"], axis=2).max(axis=1), "o-", ms=3,
                label=f"max over '{n}' (frames)")
    for n, h in monitors.items():
        ax.plot(h["time"], np.linalg.norm(h["u"], axis=1), lw=0.9, label=f"monitor '{n}'")
    _finish(ax, "Structural response: displacement magnitude", "|u| [m]")
    _save(fig, path, written)


def _plot_pressure_area(results: dict, path: Path, written: list[Path]) -> None:
    """Per structure: every frame's pressure-area curve (grey) and their envelope (black)."""
    surfaces = {n: s for n, s in sorted(results["structure"].items())
                if "contact_pressure" in s and np.any(s["contact_pressure"] > 0)}
    if not surfaces:
        return
    fig, axes = _figure(len(surfaces))
    for ax, (name, s) in zip(axes, surfaces.items()):
        pa = pressure_area(results["time"], s)
        for curve in pa["curves"]:
            ax.loglog(pa["area"], curve, color="0.75", lw=0.7)
        ax.loglog(pa["area"], pa["envelope"], "k", lw=1.6, label="envelope over the run")
        ax.set_title(f"Pressure-area on '{name}' (patch grown from the peak facet, per frame)")
        ax.set_xlabel("contact area [m$^2$]")
        ax.set_ylabel("mean pressure [Pa]")
        ax.grid(alpha=0.3, which="both")
        ax.legend(loc="best", fontsize="small")
    _save(fig, path, written)


def projection_axes(points: np.ndarray) -> tuple[int, int]:
    """The two axes (0 = x, 1 = y, 2 = z) of the largest extents of ``points``, in order."""
    ext = points.max(axis=0) - points.min(axis=0)
    a, b = np.argsort(-ext, kind="stable")[:2]
    return (int(a), int(b)) if a < b else (int(b), int(a))


def _plot_damage(results: dict, path: Path, written: list[Path]) -> None:
    ice = results["ice"]
    t = results["time"]
    x0 = np.concatenate([b["x0"] for b in ice.values()])
    i, j = projection_axes(x0)
    n = x0.shape[0]
    fig, axes = _figure(1, height=5.0)
    ax = axes[0]
    sc = None
    for b in ice.values():
        x = b["x0"] + b["u"][-1]
        sc = ax.scatter(x[:, i], x[:, j], c=b["damage"][-1], s=max(0.5, min(20.0, 2.0e4 / n)),
                        cmap="viridis", vmin=0.0, vmax=1.0, linewidths=0)
    fig.colorbar(sc, ax=ax, label="damage [-] (broken fraction of bonds)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"{AXES[i]} [m]")
    ax.set_ylabel(f"{AXES[j]} [m]")
    ax.set_title(f"Ice damage at t = {t[-1]:.4g} s (deformed positions, {AXES[i]}{AXES[j]} "
                 "projection)")
    _save(fig, path, written)


def _plot_energy(h: dict, path: Path, written: list[Path]) -> None:
    fig, axes = _figure(1, height=4.0)
    ax = axes[0]
    for k in sorted(k for k in h if k != "time"):
        ax.plot(h["time"], h[k], "o-", ms=2, lw=0.9, label=k)
    _finish(ax, "Energies of the ice and the structures", "energy [J]", ncol=2)
    _save(fig, path, written)


def write_plots(results: dict, out_dir: str | os.PathLike,
                cutoff: float | None = None) -> list[Path]:
    """Write the report plots (PNG, 150 dpi) of a results file into a directory.

    Parameters
    ----------
    results
        :func:`pdfem.post.load.load_results` of a file.
    out_dir
        Directory for the plots (created).

    Returns
    -------
    list of pathlib.Path
        The files written, among (each only when the file has the data):
        ``load_history.png`` (force components and magnitude averaged over 0.1 ms vs time,
        the per-step magnitude faint, one panel per loaded
        structure; needs a load history), ``load_spectrum.png`` (one-sided amplitude spectrum
        of the force magnitude on log-log axes, Hz, the mean left out; needs 4 or more load
        samples), ``region_reactions.png`` (the same for the reactions of the ice's fixed and
        prescribed regions, ``loads/<body>.<region>``), ``structure_response.png``
        (max von Mises and max displacement over the structure vs time from the frames, and
        the monitors; needs a structure and a frame), ``damage.png`` (ice particles at the
        last frame coloured by damage, projected on the plane of the two largest extents;
        needs ice and a frame), ``energy.png`` (the energy history; needs 1 or more rows),
        ``patch_loads.png`` (the force on each load patch), ``pressure_area.png`` (the
        pressure-area curves of the frames and their envelope; needs contact pressure),
        ``ship_motions.png`` (the 6 DOF of each free hull, :mod:`pdfem.post.motions`),
        ``shaft_loads.png`` and ``shaft_spectrum.png`` (rotating structures,
        :func:`pdfem.post.shaft.plot_shaft`).
    cutoff
        With a cut-off (Hz), the load plots also show the zero-phase low-passed |F|.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    hist = results["histories"]
    written: list[Path] = []
    structure_loads, region_loads = split_loads(hist)
    loads = {n: h for n, h in structure_loads.items() if h["time"].size}
    if loads:
        _plot_loads(loads, out / "load_history.png", written, cutoff=cutoff)
    patches = {n: h for n, h in patch_loads(hist).items() if h["time"].size}
    if patches:
        _plot_loads(patches, out / "patch_loads.png", written, "Ice force on patch '{}'",
                    cutoff)
    regions = {n: h for n, h in region_loads.items() if h["time"].size}
    if regions:
        _plot_loads(regions, out / "region_reactions.png", written,
                    "Reaction of ice region '{}' (force on the ice)")
    plot_resistance(results, out / "resistance.png", written)
    plot_motions(results, out / "ship_motions.png", written)
    plot_shaft(results, out, written)
    spectra = {n: h for n, h in loads.items() if h["time"].size >= 4}
    if spectra:
        _plot_spectrum(spectra, out / "load_spectrum.png", written)
    if results["structure"] and results["time"].size:
        _plot_response(results, out / "structure_response.png", written)
    if results["time"].size:
        _plot_pressure_area(results, out / "pressure_area.png", written)
    if results["ice"] and results["time"].size:
        _plot_damage(results, out / "damage.png", written)
    e = hist.get("energy")
    if e is not None and e["time"].size:
        _plot_energy(e, out / "energy.png", written)
    return written
