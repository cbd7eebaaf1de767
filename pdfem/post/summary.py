"""The summary figures of a results file: ice loads (peak, mean), structural peaks, damage, energy.

:func:`summarize` turns a file read by :func:`pdfem.post.load.load_results` into a JSON-ready
dict (:mod:`pdfem.post.table` prints it). SI units throughout: N, N m, Pa, m, s, J.

Definitions used in the summary:

- *peak* (the headline figure) of a load: that of the load averaged over 0.1 ms
  (``window``, :mod:`pdfem.post.windowed`), because it converges with the step: for a force
  component the averaged sample of largest absolute value, with its sign and time; for the
  magnitude ``|F| = sqrt(Fx^2 + Fy^2 + Fz^2)`` of the averaged force, its largest sample.
- *per-step peak* (``per_step_peak``, ``per_step_time``): the same of the raw per-step
  history. It is a single particle's impact over one coupling step and grows as the step
  shrinks (demo: 231 to 1,219 kN from safety factor 0.8 to 0.15 while the 0.1 ms peak moves
  1 %): shown beside the peak, marked step-dependent, never the headline.
- *mean*: the time average over the run, ``(1 / (t_K - t_1)) * integral of F dt`` over the
  load history's whole time span, integral by the trapezoid rule (a history of one sample: that
  sample). The load history holds every coupling step, from t = 0 to the end of the run.
- von Mises stress and structure displacement come from the output frames (every
  ``output_interval``): peaks between frames are not seen. Monitors and loads are per step.
  Locations are in the reference configuration: an element's centre is the mean of its nodes.
- reaction of a fixed group: peak magnitude of its (3,) reaction force over the frames.
- reaction of an ice region (``loads/<body>.<region>``, every coupling step): the force its
  support or driver exerts on the ice, with the same figures as a load (peaks, means).
- ice damage (broken fraction of the initial bonds) at the last frame: its maximum and its
  volume-weighted mean per body.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from pdfem.post.groups import AXES, histories_of, patch_loads, split_loads
from pdfem.post.ice_loads import (SURFACE_SUFFIX, filtered_figures, is_contact_surface,
                                  load_split, pressure_figures)
from pdfem.post.motions import motion_figures, ship_motions
from pdfem.post.resistance import resistance_summary
from pdfem.post.shaft import shaft_summary
from pdfem.post.windowed import signed_peak, windowed_force


def _num(x: Any) -> float | None:
    """A JSON-ready float (``None`` for NaN/Inf)."""
    x = float(x)
    return x if math.isfinite(x) else None


def _vec(v: np.ndarray) -> list[float | None]:
    """A JSON-ready list of the components of ``v``."""
    return [_num(c) for c in v]


def _at_max(t: np.ndarray, y: np.ndarray) -> dict:
    """The largest sample of ``y`` and its time: ``{"value", "time"}``."""
    i = int(np.argmax(y))
    return {"value": _num(y[i]), "time": _num(t[i])}


def time_average(time: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Time average over the span of ``time``: trapezoid integral divided by the span.

    Parameters
    ----------
    time
        (K,) sample times, s, increasing.
    values
        (K, ...) samples.

    Returns
    -------
    numpy.ndarray
        (...) the average; the single sample if K == 1, NaN if K == 0.
    """
    t = np.asarray(time, dtype=np.float64)
    y = np.asarray(values, dtype=np.float64)
    if t.size == 0:
        return np.full(y.shape[1:], np.nan)
    span = t[-1] - t[0]
    if t.size == 1 or span <= 0:
        return y.mean(axis=0)
    return np.trapezoid(y, t, axis=0) / span


def _load_figures(h: dict, cutoff: float | None = None) -> dict:
    """Peak (signed, with time) and mean of each force component and of |F| of one history;
    with a ``cutoff`` (Hz) also those of the low-passed history (``filtered``).

    The ``peak`` is that of the history averaged over :data:`pdfem.post.windowed.WINDOW`
    (``window``, s): the figure that converges with the step. The raw per-step peak stands
    beside it as ``per_step_peak`` (``per_step_time``), marked step-dependent wherever shown."""
    t, force = h["time"], h["force"]
    out: dict[str, Any] = {"samples": int(t.size)}
    if t.size == 0:
        return out
    out["start_time"], out["end_time"] = _num(t[0]), _num(t[-1])
    mean = time_average(t, force)
    tw, fw, window = windowed_force(t, force)
    out["window"] = _num(window)
    for a, name in enumerate(AXES):
        peak, when = signed_peak(tw, fw[:, a])
        raw, raw_when = signed_peak(t, force[:, a])
        out[name] = {"peak": _num(peak), "time": _num(when), "per_step_peak": _num(raw),
                     "per_step_time": _num(raw_when), "mean": _num(mean[a])}
    mag = np.linalg.norm(force, axis=1)
    magw = np.linalg.norm(fw, axis=1)
    i, j = int(np.argmax(mag)), int(np.argmax(magw))
    out["magnitude"] = {"peak": _num(magw[j]), "time": _num(tw[j]),
                        "force_at_peak": _vec(fw[j]), "per_step_peak": _num(mag[i]),
                        "per_step_time": _num(t[i]), "mean": _num(time_average(t, mag))}
    if "contacts" in h:
        out["max_contacts"] = int(np.max(h["contacts"]))
    if "area" in h:
        out["area"] = _num(h["area"][0])
    if cutoff is not None:
        out["filtered"] = filtered_figures(t, force, cutoff, _num)
    return out


def _structure_figures(results: dict, name: str, s: dict) -> dict:
    t = results["time"]
    points = s["points"]
    out: dict[str, Any] = {"kind": "elastic" if "von_mises" in s else "rigid",
                           "nodes": int(points.shape[0]), "elements": int(s["cells"].shape[0])}
    u = s["u"]
    if u.shape[0]:
        mag = np.linalg.norm(u, axis=2)
        f, n = np.unravel_index(int(np.argmax(mag)), mag.shape)
        out["max_displacement"] = {"value": _num(mag[f, n]), "time": _num(t[f]), "node": int(n),
                                   "location": _vec(points[n])}
    if "von_mises" in s and s["von_mises"].shape[0]:
        vm = s["von_mises"]
        f, e = np.unravel_index(int(np.argmax(vm)), vm.shape)
        centre = points[s["cells"][e]].mean(axis=0)
        out["max_von_mises"] = {"value": _num(vm[f, e]), "time": _num(t[f]), "element": int(e),
                                "location": _vec(centre)}
    h = results["histories"].get(f"structures/{name}")
    if h is not None and h["time"].size:
        reactions = {}
        for key in sorted(k for k in h if k.startswith("reaction_")):
            r = h[key]
            mag = np.linalg.norm(r, axis=1)
            i = int(np.argmax(mag))
            reactions[key[len("reaction_"):]] = {"peak": _num(mag[i]), "time": _num(h["time"][i]),
                                                 "force_at_peak": _vec(r[i])}
        if reactions:
            out["reactions"] = reactions
        for key in ("kinetic", "strain"):
            if key in h:
                out[f"max_{key}_energy"] = _at_max(h["time"], h[key])
    return out


def _monitor_figures(h: dict) -> dict:
    t = h["time"]
    out: dict[str, Any] = {"samples": int(t.size)}
    if t.size == 0:
        return out
    mag = np.linalg.norm(h["u"], axis=1)
    i = int(np.argmax(mag))
    out["peak_u"] = {"value": _num(mag[i]), "time": _num(t[i]), "u_at_peak": _vec(h["u"][i])}
    if "von_mises" in h:
        out["peak_von_mises"] = _at_max(t, h["von_mises"])
    return out


def _ice_figures(results: dict, body: dict) -> dict:
    n = int(body["x0"].shape[0])
    out: dict[str, Any] = {"particles": n}
    d = body["damage"]
    if d.shape[0]:
        last = d[-1]
        vol = body.get("volume")
        w = vol if vol is not None else np.ones(n)
        out["time"] = _num(results["time"][-1])
        out["max_damage"] = _num(last.max())
        out["mean_damage"] = _num(np.dot(w, last) / w.sum())
        out["damaged_particles"] = int(np.count_nonzero(last > 0.0))
    return out


def summarize(results: dict, lowpass: float | None = None) -> dict:
    """The summary figures of a results file, as a JSON-ready dict (SI units).

    Parameters
    ----------
    results
        :func:`pdfem.post.load.load_results` (or :func:`pdfem.output.read_results`) of a file.

    Returns
    -------
    dict
        ``file``, ``title``, ``frames``, ``end_time`` (s, last frame); ``loads``
        {structure: figures}, ``contacts`` {pair: figures}: per direction ``x``, ``y``, ``z``
        and ``magnitude`` the ``peak`` (N, averaged over ``window`` s), its ``time`` (s),
        the step-dependent ``per_step_peak`` (N) and ``per_step_time`` (s), and the ``mean``
        (N, time average over the run, see the module docstring); ``regions`` {``<body>.<region>``:
        the same figures of the reaction of an ice body's fixed or prescribed region (N, the
        force on the ice)}; ``resistance`` {ship hull: ice resistance -F_x over its steady phase: ``start``, ``end``
        (s), ``samples``, ``mean``, ``std``, ``peak`` (N); :mod:`pdfem.post.resistance`};
        ``motions`` {free hull: largest ``translation`` of G (m) and ``rotation`` (deg) per
        axis; :mod:`pdfem.post.motions`}; ``shaft`` {rotating structure: ice torque, thrust,
        spectral peak, blade loads; :func:`pdfem.post.shaft.shaft_figures`};
        ``structures`` {name:
        ``max_von_mises`` / ``max_displacement`` {value, time, element or node, location},
        ``reactions`` {group: {peak, time, force_at_peak}}}; ``monitors`` {probe: ``peak_u``,
        ``peak_von_mises``}; ``ice`` {body: particles, max_damage, mean_damage (volume
        weighted), damaged_particles at the last frame}; ``energy`` {key: value at the last
        frame, J}. Missing quantities (no frames yet, no von Mises on a rigid body) are
        absent; non-finite numbers are ``None``.
    """
    meta = results.get("meta", {})
    t = results["time"]
    hist = results["histories"]
    out: dict[str, Any] = {"file": results.get("file"), "title": meta.get("title", ""),
                           "version": meta.get("version", ""), "frames": int(t.size),
                           "end_time": _num(t[-1]) if t.size else None}
    loads, regions = split_loads(hist)
    contacts = histories_of(hist, "contacts", "force")
    out["loads"] = {n: _load_figures(h, lowpass) for n, h in loads.items()}
    out["regions"] = {n: _load_figures(h, lowpass) for n, h in regions.items()}
    out["contacts"] = {n: _load_figures(h, lowpass) for n, h in contacts.items()}
    out["patches"] = {n: _load_figures(h, lowpass) for n, h in patch_loads(hist).items()}
    out["load_split"] = load_split(results, contacts)
    surfaces = {n: s for n, s in results["structure"].items() if is_contact_surface(s)}
    out["contact_pressure"] = {n.removesuffix(SURFACE_SUFFIX): pressure_figures(results, n, s, _num)
                               for n, s in sorted(surfaces.items())}
    out["structures"] = {name: _structure_figures(results, name, s)
                         for name, s in sorted(results["structure"].items())
                         if name not in surfaces}
    out["monitors"] = {n: _monitor_figures(h)
                       for n, h in histories_of(hist, "monitors", "u").items()}
    out["resistance"] = {n: {k: _num(v) if isinstance(v, float) else v for k, v in f.items()}
                         for n, f in resistance_summary(results).items()}  # groups: floats
    out["motions"] = {n: motion_figures(h) for n, h in ship_motions(results).items()}
    out["shaft"] = shaft_summary(results)   # rotating structures: :mod:`pdfem.post.shaft`
    out["ice"] = {name: _ice_figures(results, b) for name, b in sorted(results["ice"].items())}
    e = hist.get("energy")
    out["energy"] = ({k: _num(v[-1]) for k, v in sorted(e.items()) if k != "time"}
                     if e is not None and e["time"].size else {})
    if out["energy"]:
        out["energy_time"] = _num(e["time"][-1])
    return out
