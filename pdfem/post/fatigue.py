"""Fatigue at monitors: rainflow counting (ASTM E1049-85) and a Palmgren-Miner damage sum.

The stress history of a monitor (``monitors/<name>``, one row per coupling step) is reduced
to its cycles by the rainflow method of ASTM E1049-85 (2017), section 5.4.4 (the `rainflow`
package: half cycles from the residue count 0.5), and each cycle of range ``ds`` (Pa) is
charged ``count / N(ds)`` against an S-N curve (:class:`SNCurve`). SI units: Pa, s.

The stress counted (``STRESSES``) is by default the *signed* principal stress of largest
magnitude of the monitor's element (``principal``), as DNV-RP-C203 (2016) sec. 2.3 and
Hobbacher, IIW recommendations (2016) sec. 3.2 use the principal (or the normal) stress range
rather than an equivalent stress; a Cartesian component (``xx`` ... ``xy``, global axes) may
be chosen instead, and ``von_mises`` (always positive: a load reversal from +s to -s shows as
no range at all) only for files written before the stress components were.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import rainflow

from pdfem.errors import InputError

COMPONENTS = ("xx", "yy", "zz", "yz", "xz", "xy")
"""Order of the six stress components in a monitor's ``stress`` column (Pa)."""

STRESSES = ("principal", *COMPONENTS, "von_mises")
"""The stresses that can be counted (``--sn-stress``)."""

SN_FORM = ("m=SLOPE,stress=RANGE_PA,cycles=N_REF[,m2=SLOPE2][,knee=N_KNEE], e.g. "
           "m=3,stress=90e6,cycles=2e6,m2=5,knee=1e7 (the DNV-RP-C203 D curve in air, "
           "FAT 90 of IIW: a stress range of 90 MPa = 90e6 Pa endured 2e6 times)")


@dataclass(frozen=True)
class SNCurve:
    """An S-N curve ``N = cycles * (stress / ds)**m`` (one slope) for ranges ``ds`` (Pa).

    With ``m2``, ranges below the knee range ``ds_k = stress * (cycles / knee)**(1/m)`` (the
    range endured ``knee`` times) follow ``N = knee * (ds_k / ds)**m2`` (DNV-RP-C203 Table 2-1:
    ``m2 = 5`` after ``knee = 1e7`` in air). DNV's ``log10 a`` (``a`` for ranges in MPa) is
    ``log10 a = log10 cycles + m * log10(stress / 1e6)``.
    """

    m: float
    stress: float  # Pa, the reference range
    cycles: float  # the cycles that range is endured
    m2: float | None = None
    knee: float = 1.0e7

    @property
    def knee_range(self) -> float:
        """The range (Pa) endured ``knee`` times on the first slope."""
        return self.stress * (self.cycles / self.knee) ** (1.0 / self.m)

    def endurance(self, ranges: np.ndarray) -> np.ndarray:
        """Cycles to failure ``N`` at each stress range (Pa); ``inf`` for a range of 0."""
        ds = np.asarray(ranges, dtype=np.float64)
        with np.errstate(divide="ignore"):
            n = self.cycles * (self.stress / ds) ** self.m
            if self.m2 is not None:
                low = ds < self.knee_range
                n[low] = self.knee * (self.knee_range / ds[low]) ** self.m2
        return n

    def as_dict(self) -> dict:
        """The curve's parameters (JSON-ready), with DNV's ``log10_a`` (``a`` for MPa)."""
        out = {"m": self.m, "stress": self.stress, "cycles": self.cycles,
               "log10_a_MPa": math.log10(self.cycles) + self.m * math.log10(self.stress / 1e6)}
        if self.m2 is not None:
            out.update(m2=self.m2, knee=self.knee, knee_range=self.knee_range)
        return out


def parse_sn(text: str, source: str | None = None) -> SNCurve:
    """The :class:`SNCurve` of ``--sn`` text ``m=3,stress=90e6,cycles=2e6[,m2=5,knee=1e7]``.

    Raises
    ------
    InputError
        Naming ``--sn`` and the valid form if a key is unknown or missing, or a value is not a
        positive number (a reference range below 1e5 Pa is taken for MPa given by mistake).
    """
    values: dict[str, float] = {}
    for part in filter(None, (p.strip() for p in str(text).split(","))):
        key, eq, val = part.partition("=")
        key = key.strip()
        if not eq or key not in ("m", "stress", "cycles", "m2", "knee") or key in values:
            raise InputError(source, "--sn", f"'{part}' is not one of the keys m, stress, "
                             f"cycles, m2, knee given once each; the form is {SN_FORM}", text)
        try:
            values[key] = float(val)
        except ValueError:
            values[key] = math.nan
        if not (math.isfinite(values[key]) and values[key] > 0):
            raise InputError(source, "--sn", f"{key} must be a positive number; the form is "
                             f"{SN_FORM}", text)
    missing = [k for k in ("m", "stress", "cycles") if k not in values]
    if missing:
        raise InputError(source, "--sn", f"{', '.join(missing)} missing; the form is {SN_FORM}",
                         text)
    if values["stress"] < 1e5:
        raise InputError(source, "--sn", "stress is the reference stress range in Pa and "
                         f"{values['stress']:g} Pa is below any S-N curve: MPa given? "
                         f"(90 MPa is 90e6); the form is {SN_FORM}", text)
    if "knee" in values and "m2" not in values:
        raise InputError(source, "--sn", f"knee needs the slope m2 after it; the form is "
                         f"{SN_FORM}", text)
    return SNCurve(**values)


def counted_stress(h: dict, stress: str) -> np.ndarray:
    """The stress history (Pa, (K,)) of monitor history ``h`` that is counted (``STRESSES``).

    ``principal``: at each step the principal stress of largest magnitude, with its sign.
    """
    if stress == "von_mises":
        return np.asarray(h["von_mises"], dtype=np.float64)
    s = np.asarray(h["stress"], dtype=np.float64)
    if stress != "principal":
        return s[:, COMPONENTS.index(stress)]
    full = np.empty((s.shape[0], 3, 3))
    for k, (i, j) in enumerate(((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))):
        full[:, i, j] = full[:, j, i] = s[:, k]
    p = np.linalg.eigvalsh(full)
    return p[np.arange(p.shape[0]), np.argmax(np.abs(p), axis=1)]


def rainflow_cycles(time: np.ndarray, series: np.ndarray) -> np.ndarray:
    """The rainflow cycles of a history (ASTM E1049-85 sec. 5.4.4, `rainflow` package).

    Returns
    -------
    numpy.ndarray
        (n, 5): range (Pa), mean (Pa), count (1 or 0.5), start and end time (s); cycles of
        range 0 (a constant history) are left out.
    """
    y = np.asarray(series, dtype=np.float64)
    ok = np.isfinite(y)
    t, y = np.asarray(time, dtype=np.float64)[ok], y[ok]
    rows = [(r, m, c, t[i], t[j]) for r, m, c, i, j in rainflow.extract_cycles(y) if r > 0] \
        if y.size > 1 else []
    return np.array(rows, dtype=np.float64).reshape(-1, 5)


def miner_damage(cycles: np.ndarray, curve: SNCurve) -> np.ndarray:
    """Palmgren-Miner damage ``count / N(range)`` of each cycle of :func:`rainflow_cycles`."""
    return cycles[:, 2] / curve.endurance(cycles[:, 0])


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def fatigue_figures(cycles: np.ndarray, curve: SNCurve, events: float = 1.0,
                    bins: int = 10, largest: int = 10) -> dict:
    """Damage, life and rainflow histogram of one monitor's cycles (JSON-ready).

    Parameters
    ----------
    cycles
        :func:`rainflow_cycles` of the counted stress (Pa, s).
    curve
        The S-N curve.
    events
        Repetitions of the simulated history (e.g. per year) that ``damage_total`` counts.
    bins
        Equal bins of range from 0 to the largest range for the ``histogram``.
    largest
        How many of the largest cycles to list.

    Returns
    -------
    dict
        ``cycles`` (sum of counts), ``max_range`` (Pa), ``damage`` (Miner sum of one history),
        ``damage_total`` (``events`` x ``damage``), ``life_events`` (histories to D = 1, None
        if no damage), ``histogram`` [{``range_low``, ``range_high`` (Pa), ``cycles``,
        ``mean`` (Pa, count-weighted), ``damage``}], ``largest`` [{``range``, ``mean``,
        ``count``, ``start``, ``end``}] by falling range.
    """
    d = miner_damage(cycles, curve)
    total = float(d.sum())
    top = float(cycles[:, 0].max()) if cycles.size else 0.0
    edges = np.linspace(0.0, top if top > 0 else 1.0, bins + 1)
    which = np.clip(np.searchsorted(edges, cycles[:, 0], side="right") - 1, 0, bins - 1)
    hist = []
    for b in range(bins):
        sel = which == b
        n = float(cycles[sel, 2].sum())
        mean = float(np.dot(cycles[sel, 1], cycles[sel, 2]) / n) if n else None
        hist.append({"range_low": float(edges[b]), "range_high": float(edges[b + 1]),
                     "cycles": n, "mean": mean, "damage": float(d[sel].sum())})
    order = np.argsort(-cycles[:, 0], kind="stable")[:largest]
    big = [dict(zip(("range", "mean", "count", "start", "end"), map(float, cycles[i])))
           for i in order]
    return {"cycles": float(cycles[:, 2].sum()), "max_range": top, "damage": total,
            "events": events, "damage_total": total * events,
            "life_events": _num(1.0 / total) if total > 0 else None,
            "histogram": hist, "largest": big}


def monitor_cycles(results: dict, stress: str | None = None,
                   monitors: list[str] | None = None) -> tuple[str, dict[str, np.ndarray]]:
    """The rainflow cycles of the counted stress at the monitors of a results file.

    Parameters
    ----------
    results
        :func:`pdfem.post.load.load_results` of a file.
    stress
        One of ``STRESSES``; ``None``: ``principal`` if the monitors have stress components,
        else ``von_mises`` (files written before them).
    monitors
        Monitor names to count; ``None``: all.

    Returns
    -------
    stress : str
        The stress counted.
    cycles : dict
        {monitor: :func:`rainflow_cycles`}, by name.

    Raises
    ------
    InputError
        Naming ``--sn``, ``--sn-monitor`` or ``--sn-stress`` if the file has no monitor, a
        monitor is not in the file, or the monitors lack the stress asked for.
    """
    file = results.get("file")
    hist = {g[len("monitors/"):]: h for g, h in sorted(results["histories"].items())
            if g.startswith("monitors/")}
    if not hist:
        raise InputError(file, "--sn", "the results file has no monitor to count: add a "
                         "[[monitor]] (name, structure, point) to the case and run it again")
    unknown = [n for n in monitors or () if n not in hist]
    if unknown:
        raise InputError(file, "--sn-monitor", f"no monitor {unknown[0]!r} in the file; its "
                         f"monitors are {', '.join(hist)}", unknown[0])
    names = list(monitors) if monitors else list(hist)
    has_components = all("stress" in hist[n] for n in names)
    stress = stress or ("principal" if has_components else "von_mises")
    if stress not in STRESSES:
        raise InputError(file, "--sn-stress", f"the stress counted is one of "
                         f"{', '.join(STRESSES)}", stress)
    if stress != "von_mises" and not has_components:
        raise InputError(file, "--sn-stress", "the monitors of this file have no stress "
                         "components (written before they were): only von_mises can be "
                         "counted, or run the case again", stress)
    return stress, {n: rainflow_cycles(hist[n]["time"], counted_stress(hist[n], stress))
                    for n in names}


def fatigue_summary(stress: str, cycles: dict[str, np.ndarray], curve: SNCurve,
                    events: float = 1.0, bins: int = 10) -> dict:
    """The ``fatigue`` block of ``pdfem post --sn`` (JSON-ready): ``curve``
    (:meth:`SNCurve.as_dict`), ``stress`` counted, ``events`` and ``monitors`` {name:
    :func:`fatigue_figures`} of the ``(stress, cycles)`` of :func:`monitor_cycles`."""
    return {"curve": curve.as_dict(), "stress": stress, "events": events,
            "monitors": {n: fatigue_figures(c, curve, events, bins) for n, c in cycles.items()}}
