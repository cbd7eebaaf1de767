"""Shaft and blade loads in ``pdfem post``: ice torque and thrust of a rotating structure (a
propeller) against time and shaft angle, their amplitude spectrum with the blade passing
frequency, and the summary figures (docs/rotating_structures.md, "Shaft and blade loads").

Reads the histories ``shaft/<name>`` and ``shaft/<name>.blade<k>`` that a run writes every
coupling step for an elastic structure with a rotating ``motion``
(:mod:`pdfem.motion.shaft_loads`). The shaft speed is the slope of ``frame_angle`` at the end of
the run; the number of blades Z is the number of blade histories; the blade passing frequency
is ``Z rpm / 60`` (Hz). SI units: N, N m, s, Hz, Pa, m; angles shown in degrees.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pdfem.post.spectrum import amplitude_spectrum
from pdfem.post.windowed import peak_pair, signed_peak, windowed_force

PREFIX = "shaft/"
"""History groups of rotating structures: ``shaft/<name>``, ``shaft/<name>.<blade>``."""

ICE_LOADS = ("ice_torque", "thrust")
"""Shaft histories that are the ice's per-step loads (impulse / step): plotted and reported
averaged over 0.1 ms (:mod:`pdfem.post.windowed`)."""

HARMONICS = 4
"""Multiples of the blade passing frequency marked on the spectrum plot."""


def shaft_histories(results: dict) -> dict[str, tuple[dict, dict[str, dict]]]:
    """``{structure: (shaft history, {blade: blade history})}`` of a results file
    (:func:`pdfem.post.load.load_results`) with samples."""
    hist = results["histories"]
    out = {}
    for key, h in sorted(hist.items()):
        name = key[len(PREFIX):]
        if key.startswith(PREFIX) and "." not in name and h["time"].size:
            blades = {k[len(key) + 1:]: b for k, b in sorted(hist.items())
                      if k.startswith(key + ".")}
            out[name] = (h, blades)
    return out


def shaft_speed(h: dict) -> float:
    """The shaft speed at the end of the history (rad/s): the slope of ``frame_angle``."""
    t, a = np.asarray(h["time"]), np.asarray(h["frame_angle"])
    if t.size < 2:
        return 0.0
    return float((a[-1] - a[-2]) / (t[-1] - t[-2]))


def _mean(t: np.ndarray, y: np.ndarray) -> float:
    """Time average (trapezoid rule) of ``y`` over the span of ``t``; one sample: itself."""
    return float(y[0]) if t.size < 2 else float(np.trapezoid(y, t) / (t[-1] - t[0]))


def shaft_figures(h: dict, blades: dict[str, dict]) -> dict:
    """Summary figures of one rotating structure.

    Returns
    -------
    dict
        ``rpm`` (1/min), ``blades`` Z, ``blade_passing_frequency`` (Hz), ``window`` (s),
        ``peak_ice_torque`` {value N m, time s}, ``mean_ice_torque`` and ``mean_shaft_torque``
        (N m), ``mean_thrust`` and ``peak_thrust`` (N, |largest|, signed); the peaks of the
        ice's loads are those of the loads averaged over ``window``
        (:func:`pdfem.post.windowed.peak_pair`, step independent), ``per_step`` holds the
        step-dependent per-step ``peak_ice_torque`` and ``peak_thrust``;
        ``spectral_peak_frequency``
        (Hz, largest amplitude of the ice torque's spectrum above 0 Hz; None for < 4 samples),
        ``max_von_mises`` {value Pa, time s, location m (frame axes)}, and per blade
        ``peak_spindle_torque``, ``peak_bending_out_of_plane``, ``peak_bending_in_plane``
        (N m, signed, largest |value| averaged over ``window``; the ice load's moments),
        ``peak_root_moment`` (N m, per component of the supports' root moment, the structure's
        response: per step), ``root_stress`` (the nominal root stress's peaks,
        :func:`root_stress_peaks`) and ``max_von_mises`` (Pa).
    """
    t = np.asarray(h["time"])
    q, thrust = np.asarray(h["ice_torque"]), np.asarray(h["thrust"])
    rpm = shaft_speed(h) * 60.0 / (2.0 * math.pi)
    z = max(len(blades), 1)
    k = int(np.argmax(h["max_von_mises"]))
    peak_f = None
    if t.size >= 4:
        f, amp = amplitude_spectrum(t, q)
        peak_f = float(f[1 + int(np.argmax(amp[1:]))])
    torque, push = peak_pair(t, q), peak_pair(t, thrust)

    def windowed_peak(y) -> float:
        return signed_peak(*windowed_force(t, np.asarray(y))[:2])[0]

    return {"rpm": rpm, "blades": z, "blade_passing_frequency": z * rpm / 60.0,
            "window": torque["window"],
            "peak_ice_torque": {"value": torque["peak"], "time": torque["time"]},
            "mean_ice_torque": _mean(t, q), "mean_shaft_torque": _mean(t, h["shaft_torque"]),
            "mean_thrust": _mean(t, thrust), "peak_thrust": push["peak"],
            "per_step": {"peak_ice_torque": {"value": torque["per_step_peak"],
                                             "time": torque["per_step_time"]},
                         "peak_thrust": push["per_step_peak"]},
            "spectral_peak_frequency": peak_f,
            "max_von_mises": {"value": float(h["max_von_mises"][k]), "time": float(t[k]),
                              "location": np.asarray(h["max_von_mises_location"][k]).tolist()},
            "blade": {b: {"peak_spindle_torque": windowed_peak(g["spindle_torque"]),
                          "peak_bending_out_of_plane": windowed_peak(g["bending_out_of_plane"]),
                          "peak_bending_in_plane": windowed_peak(g["bending_in_plane"]),
                          "peak_root_moment": [signed_peak(t, c)[0] for c in
                                               np.asarray(g["root_moment"]).T],
                          **root_stress_peaks(t, g),
                          "max_von_mises": float(np.max(g["max_von_mises"]))}
                      for b, g in blades.items()}}


def root_stress_peaks(t: np.ndarray, blade: dict) -> dict:
    """``{"root_stress": {"tension": {value, time}, "compression": {value, time}}}`` (Pa, s):
    the largest nominal root stress in tension and in compression over a blade's history
    (per step: the structure's response; :mod:`pdfem.fem.section_stress`); empty for a blade
    whose root is no surface group (no such history)."""
    if "root_stress_tension" not in blade:
        return {}
    hi, lo = np.asarray(blade["root_stress_tension"]), np.asarray(blade["root_stress_compression"])
    i, j = int(np.argmax(hi)), int(np.argmin(lo))
    return {"root_stress": {"tension": {"value": float(hi[i]), "time": float(t[i])},
                            "compression": {"value": float(lo[j]), "time": float(t[j])}}}


def shaft_summary(results: dict) -> dict[str, dict]:
    """``{structure: shaft_figures}`` of every rotating structure of a results file."""
    return {n: shaft_figures(h, b) for n, (h, b) in shaft_histories(results).items()}


def shaft_lines(summary: dict) -> list[str]:
    """Text lines of the ``shaft`` part of :func:`pdfem.post.summary.summarize`."""
    lines = []
    for name, f in summary.get("shaft", {}).items():
        sp = f["spectral_peak_frequency"]
        vm = f["max_von_mises"]
        lines += ["", f"Shaft loads of '{name}' ({f['blades']} blade{'s' * (f['blades'] != 1)}, {f['rpm']:.4g} rpm, "
                      f"blade passing frequency {f['blade_passing_frequency']:.4g} Hz)",
                  f"  peak ice torque ({f['window'] * 1e3:.3g} ms mean) "
                  f"{f['peak_ice_torque']['value']:.4g} N m at t = "
                  f"{f['peak_ice_torque']['time']:.4g} s (per-step peak "
                  f"{f['per_step']['peak_ice_torque']['value']:.4g} N m: step-dependent); "
                  "mean ice torque "
                  f"{f['mean_ice_torque']:.4g} N m, mean shaft torque "
                  f"{f['mean_shaft_torque']:.4g} N m",
                  f"  mean thrust {f['mean_thrust']:.4g} N, peak ({f['window'] * 1e3:.3g} ms "
                  f"mean) {f['peak_thrust']:.4g} N; "
                  f"ice torque spectrum peaks at "
                  + ("-" if sp is None else f"{sp:.4g} Hz"),
                  f"  max von Mises {vm['value']:.4g} Pa at t = {vm['time']:.4g} s, element at "
                  f"{[round(c, 4) for c in vm['location']]} m (frame)"]
        for b, g in f["blade"].items():
            lines.append(f"  {b}: spindle torque {g['peak_spindle_torque']:.4g} N m, root "
                         f"bending out of plane {g['peak_bending_out_of_plane']:.4g} N m, in "
                         f"plane {g['peak_bending_in_plane']:.4g} N m (ice load); at the "
                         f"supports {', '.join(f'{c:.4g}' for c in g['peak_root_moment'])} "
                         f"N m; max von Mises "
                         f"{g['max_von_mises']:.4g} Pa")
            if "root_stress" in g:
                rs = g["root_stress"]
                lines.append(f"    nominal root stress (beam method) {rs['tension']['value']:.4g} "
                             f"Pa at t = {rs['tension']['time']:.4g} s, "
                             f"{rs['compression']['value']:.4g} Pa at t = "
                             f"{rs['compression']['time']:.4g} s")
    return lines


def plot_shaft(results: dict, out: Path, written: list[Path]) -> None:
    """``shaft_loads.png`` (ice and shaft torque and thrust against time and against the shaft
    angle, one line per revolution) and ``shaft_spectrum.png`` (amplitude spectra of the ice
    torque and thrust, the blade passing frequency and its harmonics marked) of every rotating
    structure; nothing without one."""
    shafts = shaft_histories(results)
    if not shafts:
        return
    from matplotlib.figure import Figure  # no pyplot: no global figure state, Agg canvas
    fig = Figure(figsize=(11.0, 3.2 * 2 * len(shafts) + 0.6), layout="constrained")
    axes = fig.subplots(2 * len(shafts), 2, squeeze=False)
    spec = Figure(figsize=(8.0, 3.2 * 2 * len(shafts) + 0.6), layout="constrained")
    saxes = spec.subplots(2 * len(shafts), 1, squeeze=False)[:, 0]
    for n, (name, (h, blades)) in enumerate(shafts.items()):
        t = np.asarray(h["time"])
        deg = np.degrees(np.asarray(h["frame_angle"]))
        rev = np.floor(deg / 360.0)
        bpf = max(len(blades), 1) * shaft_speed(h) / (2.0 * math.pi)
        for row, (keys, unit) in enumerate(((("ice_torque", "shaft_torque"), "N m"),
                                            (("thrust",), "N"))):
            ax_t, ax_a = axes[2 * n + row]
            for key in keys:
                y = np.asarray(h[key])
                k = 0
                if key in ICE_LOADS:    # the ice's loads: averaged over 0.1 ms, per step faint
                    ax_t.plot(t, y, color="0.8", lw=0.5, label=f"{key.replace('_', ' ')} per "
                                                                "step (step-dependent)")
                    tw, y, w = windowed_force(t, y)
                    k = t.size - tw.size
                ax_t.plot(t[k:], y, lw=0.8, label=key.replace("_", " ")
                          + (f" ({w * 1e3:.3g} ms mean)" if key in ICE_LOADS else ""))
                revs = np.unique(rev[k:])
                for r in revs:
                    on = rev[k:] == r
                    line = ax_a.plot(deg[k:][on] - 360.0 * r, y[on], lw=0.8,
                                     color=ax_t.lines[-1].get_color(), alpha=0.9 if
                                     r == revs[-1] else 0.4)
                    if r == revs[0]:
                        line[0].set_label(f"{key.replace('_', ' ')} ({revs.size} rev.)")
            ax_t.set_xlabel("time [s]")
            ax_a.set_xlabel("shaft angle [deg] (per revolution)")
            if deg[-1] - deg[0] >= 360.0:   # a revolution or more: the whole circle
                ax_a.set_xlim(0.0, 360.0)
            for ax in (ax_t, ax_a):
                ax.set_ylabel(f"[{unit}]")
                ax.grid(alpha=0.3)
                ax.legend(fontsize=7)
            ax_t.set_title(f"'{name}': {' and '.join(keys).replace('_', ' ')}")
            f, amp = amplitude_spectrum(t, np.asarray(h[keys[0]]))
            ax_s = saxes[2 * n + row]
            if f.size > 1:
                ax_s.plot(f[1:], amp[1:], "k", lw=0.9)
            for m in range(1, HARMONICS + 1):
                if bpf > 0.0:
                    ax_s.axvline(m * bpf, color="r", ls="--", lw=0.7,
                                 label="blade passing frequency and harmonics" if m == 1 else None)
            ax_s.set_title(f"Spectrum of the {keys[0].replace('_', ' ')} on '{name}' "
                           f"(BPF {bpf:.4g} Hz)")
            ax_s.set_xlabel("frequency [Hz]")
            ax_s.set_ylabel(f"amplitude [{unit}]")
            ax_s.grid(alpha=0.3)
            if bpf > 0.0:
                ax_s.legend(fontsize=7)
    fig.savefig(out / "shaft_loads.png", dpi=120)
    written.append(out / "shaft_loads.png")
    spec.savefig(out / "shaft_spectrum.png", dpi=120)
    written.append(out / "shaft_spectrum.png")
