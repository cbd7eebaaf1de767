"""Post-processing of a results file: summary figures, report plots and a CSV of the histories.

``pdfem post RESULTS.h5 [--plots DIR] [--csv FILE] [--json]`` uses these functions:
:func:`load_results` (read a file, or raise :class:`~pdfem.errors.InputError` naming it),
:func:`summarize` (the figures, a JSON-ready dict), :func:`format_summary` (the table),
:func:`write_csv` (the per-step histories), and from :mod:`pdfem.post.plots`
:func:`write_plots` (PNG plots) and :func:`amplitude_spectrum`. SI units throughout: N, N m, Pa, m, s, J.

Definitions used in the summary:

- *peak* of a force component: the sample of largest absolute value, reported with its sign
  and time; *peak* of the magnitude ``|F| = sqrt(Fx^2 + Fy^2 + Fz^2)``: its largest sample.
- *mean*: the time average over the run, ``(1 / (t_K - t_1)) * integral of F dt`` over the
  load history's whole time span, integral by the trapezoid rule (a history of one sample: that
  sample). The load history holds every coupling step, from t = 0 to the end of the run.
- von Mises stress and structure displacement come from the output frames (every
  ``output_interval``): peaks between frames are not seen. Monitors and loads are per step.
  Locations are in the reference configuration: an element's centre is the mean of its nodes.
- reaction of a fixed group: peak magnitude of its (3,) reaction force over the frames.
- ice damage (broken fraction of the initial bonds) at the last frame: its maximum and its
  volume-weighted mean per body.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from pdfem.errors import InputError
from pdfem.output.results import read_results
from pdfem.post.plots import amplitude_spectrum, projection_axes, write_plots  # noqa: F401 (API)

LOAD_PREFIXES = ("loads/", "contacts/", "monitors/")
"""History groups written at every coupling step (the CSV columns)."""

UNITS = {"force": "N", "moment": "N m", "contacts": "-", "u": "m", "von_mises": "Pa"}
"""Unit of each per-step history key (``-``: a count)."""

_AXES = ("x", "y", "z")


# -- reading ------------------------------------------------------------------------------


def load_results(path: str | os.PathLike) -> dict:
    """Read a pdfem results file, refusing anything else with a message that names the file.

    Parameters
    ----------
    path
        The HDF5 results file a run wrote (``results/<case>/results.h5``).

    Returns
    -------
    dict
        :func:`pdfem.output.results.read_results` of the file, with ``"file"`` (the path as given) added.

    Raises
    ------
    InputError
        If the file does not exist, is not HDF5, or is HDF5 without pdfem's ``/meta`` and
        ``/time``, or cannot be read.
    """
    p = Path(path)
    name = str(path)
    hint = "give the results.h5 that 'pdfem run' wrote (results/<case>/results.h5)"
    if not p.is_file():
        raise InputError(name, None, f"no such results file; {hint}")
    if p.suffix.lower() == ".xdmf":
        raise InputError(name, None, "this is the XDMF view of a results file; give the .h5 "
                         "file beside it")
    try:
        is_hdf5 = h5py.is_hdf5(p)
    except OSError as exc:
        raise InputError(name, None, f"cannot read the file ({exc})") from None
    if not is_hdf5:
        raise InputError(name, None, f"not an HDF5 file, so not a pdfem results file; {hint}")
    try:
        try:
            f = h5py.File(p, "r")
        except BlockingIOError:  # being written by a run: read without the file lock
            f = h5py.File(p, "r", locking=False)
        with f:
            missing = [k for k in ("meta", "time", "ice") if k not in f]
        if missing:
            raise InputError(name, None, "an HDF5 file but not a pdfem results file (no "
                             + ", ".join(f"/{k}" for k in missing) + f"); {hint}")
        results = read_results(p)
    except InputError:
        raise
    except (OSError, KeyError, ValueError, TypeError) as exc:
        raise InputError(name, None, f"cannot be read as a pdfem results file ({exc})") from None
    results["file"] = name
    return results


# -- summary ------------------------------------------------------------------------------


def _num(x: Any) -> float | None:
    """A JSON-ready float (``None`` for NaN/Inf)."""
    x = float(x)
    return x if math.isfinite(x) else None


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


def _peak_signed(t: np.ndarray, y: np.ndarray) -> dict:
    i = int(np.argmax(np.abs(y)))
    return {"peak": _num(y[i]), "time": _num(t[i])}


def _load_figures(h: dict) -> dict:
    """Peak (signed, with time) and mean of each force component and of |F| of one history."""
    t, force = h["time"], h["force"]
    out: dict[str, Any] = {"samples": int(t.size)}
    if t.size == 0:
        return out
    out["start_time"], out["end_time"] = _num(t[0]), _num(t[-1])
    mean = time_average(t, force)
    for a, name in enumerate(_AXES):
        out[name] = _peak_signed(t, force[:, a]) | {"mean": _num(mean[a])}
    mag = np.linalg.norm(force, axis=1)
    i = int(np.argmax(mag))
    out["magnitude"] = {"peak": _num(mag[i]), "time": _num(t[i]),
                        "mean": _num(time_average(t, mag)),
                        "force_at_peak": [_num(v) for v in force[i]]}
    if "contacts" in h:
        out["max_contacts"] = int(np.max(h["contacts"]))
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
                                   "location": [_num(v) for v in points[n]]}
    if "von_mises" in s and s["von_mises"].shape[0]:
        vm = s["von_mises"]
        f, e = np.unravel_index(int(np.argmax(vm)), vm.shape)
        centre = points[s["cells"][e]].mean(axis=0)
        out["max_von_mises"] = {"value": _num(vm[f, e]), "time": _num(t[f]), "element": int(e),
                                "location": [_num(v) for v in centre]}
    h = results["histories"].get(f"structures/{name}")
    if h is not None and h["time"].size:
        reactions = {}
        for key in sorted(k for k in h if k.startswith("reaction_")):
            r = h[key]
            mag = np.linalg.norm(r, axis=1)
            i = int(np.argmax(mag))
            reactions[key[len("reaction_"):]] = {"peak": _num(mag[i]), "time": _num(h["time"][i]),
                                                 "force_at_peak": [_num(v) for v in r[i]]}
        if reactions:
            out["reactions"] = reactions
        for key in ("kinetic", "strain"):
            if key in h:
                i = int(np.argmax(h[key]))
                out[f"max_{key}_energy"] = {"value": _num(h[key][i]), "time": _num(h["time"][i])}
    return out


def _monitor_figures(h: dict) -> dict:
    t = h["time"]
    out: dict[str, Any] = {"samples": int(t.size)}
    if t.size == 0:
        return out
    mag = np.linalg.norm(h["u"], axis=1)
    i = int(np.argmax(mag))
    out["peak_u"] = {"value": _num(mag[i]), "time": _num(t[i]),
                     "u_at_peak": [_num(v) for v in h["u"][i]]}
    if "von_mises" in h:
        j = int(np.argmax(h["von_mises"]))
        out["peak_von_mises"] = {"value": _num(h["von_mises"][j]), "time": _num(t[j])}
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


def summarize(results: dict) -> dict:
    """The summary figures of a results file, as a JSON-ready dict (SI units).

    Parameters
    ----------
    results
        :func:`load_results` (or :func:`pdfem.output.results.read_results`) of a file.

    Returns
    -------
    dict
        ``file``, ``title``, ``frames``, ``end_time`` (s, last frame); ``loads``
        {structure: figures}, ``contacts`` {pair: figures}: per direction ``x``, ``y``, ``z``
        and ``magnitude`` the ``peak`` (N), its ``time`` (s) and the ``mean`` (N, time
        average over the run, see the module docstring); ``structures`` {name:
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
    out["loads"] = {g[len("loads/"):]: _load_figures(h) for g, h in sorted(hist.items())
                    if g.startswith("loads/") and "force" in h}
    out["contacts"] = {g[len("contacts/"):]: _load_figures(h) for g, h in sorted(hist.items())
                       if g.startswith("contacts/") and "force" in h}
    out["structures"] = {name: _structure_figures(results, name, s)
                         for name, s in sorted(results["structure"].items())}
    out["monitors"] = {g[len("monitors/"):]: _monitor_figures(h) for g, h in sorted(hist.items())
                       if g.startswith("monitors/") and "u" in h}
    out["ice"] = {name: _ice_figures(results, b) for name, b in sorted(results["ice"].items())}
    e = hist.get("energy")
    out["energy"] = ({k: _num(v[-1]) for k, v in sorted(e.items()) if k != "time"}
                     if e is not None and e["time"].size else {})
    if out["energy"]:
        out["energy_time"] = _num(e["time"][-1])
    return out


def _g(x: float | None) -> str:
    return "-" if x is None else f"{x:.4g}"


def _loc(v: list | None) -> str:
    return "-" if v is None else "(" + ", ".join(f"{c:.4g}" for c in v) + ")"


def _table(header: list[str], rows: list[list[str]], indent: str = "  ") -> list[str]:
    """Rows of text cells as aligned lines: first column left-aligned, the others right."""
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]

    def line(r: list[str]) -> str:
        return indent + "  ".join(c.ljust(w) if i == 0 else c.rjust(w)
                                  for i, (c, w) in enumerate(zip(r, widths)))
    return [line(header), *(line(r) for r in rows)]


def _load_lines(what: str, name: str, f: dict) -> list[str]:
    if f["samples"] == 0:
        return [f"{what} '{name}': no samples"]
    lines = [f"{what} '{name}' ({f['samples']} steps, t = {_g(f['start_time'])} to "
             f"{_g(f['end_time'])} s; mean = time average over the run)"]
    rows = [[d, _g(f[d]["peak"]), _g(f[d]["time"]), _g(f[d]["mean"])]
            for d in (*_AXES, "magnitude")]
    lines += _table(["direction", "peak [N]", "at t [s]", "mean [N]"], rows)
    if "max_contacts" in f:
        lines.append(f"  most particles in contact at once: {f['max_contacts']}")
    return lines


def format_summary(summary: dict) -> str:
    """The summary as text tables for the terminal (units in the headers).

    Parameters
    ----------
    summary
        :func:`summarize` of a results file.

    Returns
    -------
    str
        The tables, one section per quantity, without a trailing newline.
    """
    s = summary
    head = f"Results {s['file']}" if s.get("file") else "Results"
    if s.get("title"):
        head += f" - {s['title']}"
    lines = [head, f"  {s['frames']} frames, last at t = {_g(s['end_time'])} s"]
    if not s["loads"] and not s["structures"]:
        lines.append("  no structure in this run (ice only)")
    for name, f in s["loads"].items():
        lines += ["", *_load_lines("Ice force on structure", name, f)]
    for name, f in s["contacts"].items():
        lines += ["", *_load_lines("Ice force in contact pair", name, f)]
    rows = []
    for name, st in s["structures"].items():
        vm = st.get("max_von_mises", {})
        ud = st.get("max_displacement", {})
        rows.append([name, st["kind"], _g(vm.get("value")), _g(vm.get("time")),
                     _loc(vm.get("location")), _g(ud.get("value")), _g(ud.get("time")),
                     _loc(ud.get("location"))])
    if rows:
        lines += ["", "Structures (from the output frames; locations in the reference "
                      "configuration: element centre, node)"]
        lines += _table(["structure", "kind", "max von Mises [Pa]", "at t [s]", "element at [m]",
                         "max |u| [m]", "at t [s]", "node at [m]"], rows)
    rows = [[f"{name}/{g}", _g(r["peak"]), _g(r["time"]), _loc(r["force_at_peak"])]
            for name, st in s["structures"].items() for g, r in st.get("reactions", {}).items()]
    if rows:
        lines += ["", "Reaction forces of the fixed groups (peak magnitude over the frames)"]
        lines += _table(["structure/group", "peak |R| [N]", "at t [s]", "R at peak [N]"], rows)
    rows = []
    for name, m in s["monitors"].items():
        pu, pv = m.get("peak_u", {}), m.get("peak_von_mises", {})
        rows.append([name, _g(pu.get("value")), _g(pu.get("time")), _g(pv.get("value")),
                     _g(pv.get("time"))])
    if rows:
        lines += ["", "Monitors (every coupling step)"]
        lines += _table(["monitor", "peak |u| [m]", "at t [s]", "peak von Mises [Pa]",
                         "at t [s]"], rows)
    rows = [[name, str(b["particles"]), _g(b.get("max_damage")), _g(b.get("mean_damage")),
             str(b.get("damaged_particles", "-"))] for name, b in s["ice"].items()]
    if rows:
        lines += ["", "Ice at the last frame (damage = broken fraction of the initial bonds)"]
        lines += _table(["body", "particles", "max damage [-]", "mean damage [-] (by volume)",
                         "damaged particles"], rows)
    if s["energy"]:
        lines += ["", f"Energies at t = {_g(s.get('energy_time'))} s"]
        lines += _table(["quantity", "value [J]"], [[k, _g(v)] for k, v in s["energy"].items()])
    return "\n".join(lines)


# -- per-step histories as one table -------------------------------------------------------


def _columns_of(group: str, key: str, a: np.ndarray) -> list[tuple[str, np.ndarray]]:
    unit = UNITS.get(key)
    suffix = f" [{unit}]" if unit else ""
    if a.ndim == 1:
        return [(f"{group}/{key}{suffix}", a)]
    flat = a.reshape(a.shape[0], -1)
    names = _AXES if flat.shape[1] == 3 else tuple(str(i) for i in range(flat.shape[1]))
    return [(f"{group}/{key}_{c}{suffix}", flat[:, i]) for i, c in enumerate(names)]


def history_table(results: dict) -> tuple[list[str], np.ndarray]:
    """The per-step histories (loads, contact pairs, monitors) as one table.

    Parameters
    ----------
    results
        :func:`load_results` of a file.

    Returns
    -------
    names : list of str
        ``"time [s]"`` then one name per column, ``<group>/<key>[_x|_y|_z] [<unit>]``, e.g.
        ``loads/panel/force_x [N]``; groups in the order loads, contacts, monitors.
    table : numpy.ndarray
        (K, len(names)) values; rows are the union of the groups' step times (the same
        steps in a file from :func:`pdfem.run.driver.run_case`), NaN where a group has no row.
    """
    hist = results["histories"]
    groups = [g for p in LOAD_PREFIXES for g in sorted(hist) if g.startswith(p)]
    times = np.unique(np.concatenate([hist[g]["time"] for g in groups])) if groups \
        else np.zeros(0)
    names, cols = ["time [s]"], [times]
    for g in groups:
        h = hist[g]
        rows = np.searchsorted(times, h["time"])
        for key in sorted(k for k in h if k != "time"):
            for name, values in _columns_of(g, key, h[key]):
                col = np.full(times.size, np.nan)
                col[rows] = values
                names.append(name)
                cols.append(col)
    return names, np.column_stack(cols) if cols[0].size else np.zeros((0, len(names)))


def write_csv(results: dict, path: str | os.PathLike) -> list[str]:
    """Write the per-step histories (:func:`history_table`) to one CSV file.

    Parameters
    ----------
    results
        :func:`load_results` of a file.
    path
        The CSV file to write (overwritten). One header line of column names with units, then
        one line per step; numbers with 17 significant digits (they read back exactly), NaN
        as ``nan``.

    Returns
    -------
    list of str
        The column names.
    """
    names, table = history_table(results)
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        np.savetxt(fh, table, fmt="%.17g", delimiter=",", header=",".join(names), comments="")
    return names
