"""The ice-engineering load figures of a results file: contact pressure, pressure–area, patches,
filtered peaks and the split of a structure's load over its contact pairs.

* ``contact_pressure`` per structure (from ``/structure/<name>.contact``): the largest facet
  pressure of the run (Pa; the pressure of a frame is the facet's mean over the frame
  interval, :mod:`pdfem.coupling.facet_loads`), its time and place, the largest contact area
  (m^2) and the pressure–area envelope (:mod:`pdfem.post.pressure_area`).
* ``patches``: the load figures of each load patch ``<structure>.<patch>`` (as for a
  structure's load) and its area.
* ``filtered`` (with a cut-off, ``pdfem post --lowpass HZ``), added to each load's figures:
  the peaks of the zero-phase low-passed history (:mod:`pdfem.post.lowpass`) next to the raw
  ones, and the peak of the residual raw - filtered (the impacts).
* ``load_split`` per structure: its contact pairs' shares of the load. pdfem's contact pairs
  are one per (ice body, structure), so the load *can* be split only by ice body: with a
  level-ice sheet and separate bodies for floes or fragments placed in the case, the pair
  with the largest impulse is the main contact load and the others are the fragment hits.
  Pieces broken off a body during the run stay in that body's pair and cannot be told apart
  by pair; for them the residual of the low-pass filter (``filtered``) is the measure.
Units: SI (N, N s, Pa, m^2, s, Hz).
"""

from __future__ import annotations

import tomllib
from typing import Any, Callable

import numpy as np

from pdfem.post.groups import AXES
from pdfem.post.lowpass import lowpass
from pdfem.post.pressure_area import pressure_area

SURFACE_SUFFIX = ".contact"
"""Name suffix of a structure's contact surface in the results (``<structure>.contact``)."""


def is_contact_surface(s: dict) -> bool:
    """Whether a results structure is a contact surface (it has ``contact_pressure``)."""
    return "contact_pressure" in s


def filtered_figures(t: np.ndarray, force: np.ndarray, cutoff: float, num: Callable) -> dict:
    """Peaks of the low-passed force (per component and magnitude) and of the residual."""
    f = lowpass(t, force, cutoff)
    out: dict[str, Any] = {"cutoff": num(cutoff)}
    for a, name in enumerate(AXES):
        i = int(np.argmax(np.abs(f[:, a])))
        out[name] = {"peak": num(f[i, a]), "time": num(t[i])}
    mag = np.linalg.norm(f, axis=1)
    i = int(np.argmax(mag))
    res = np.linalg.norm(force - f, axis=1)
    j = int(np.argmax(res))
    out["magnitude"] = {"peak": num(mag[i]), "time": num(t[i])}
    out["residual"] = {"peak": num(res[j]), "time": num(t[j])}
    return out


def pressure_figures(results: dict, name: str, s: dict, num: Callable) -> dict:
    """The contact-pressure figures of the contact surface ``s`` of structure ``name``."""
    t = results["time"]
    p = s["contact_pressure"]
    out: dict[str, Any] = {"facets": int(s["cells"].shape[0])}
    if not p.shape[0]:
        return out
    f, e = np.unravel_index(int(np.argmax(p)), p.shape)
    centre = s["points"][s["cells"][e]].mean(axis=0)
    pa = pressure_area(t, s)
    k = int(np.argmax(pa["contact_area"]))
    out["max_pressure"] = {"value": num(p[f, e]), "time": num(t[f]), "facet": int(e),
                           "location": [num(c) for c in centre]}
    out["max_contact_area"] = {"value": num(pa["contact_area"][k]), "time": num(t[k])}
    out["pressure_area"] = {
        "method": "patch grown from the peak facet, envelope over the frames "
                  "(pdfem.post.pressure_area)",
        "area": [num(a) for a in pa["area"]],
        "envelope": [num(v) for v in pa["envelope"]],
        "time": [num(t[j]) if j >= 0 else None for j in pa["envelope_frame"]]}
    return out


def pair_structures(case_text: str) -> dict[str, str]:
    """``{contact pair: structure}`` from the case text stored in the results (``[[contact]]``
    entries, or without them every ice body with every structure as ``"<ice>-<structure>"``)."""
    try:
        case = tomllib.loads(case_text or "")
    except tomllib.TOMLDecodeError:
        return {}
    contacts = case.get("contact", [])
    if contacts:
        return {c.get("name") or f"{c.get('ice')}-{c.get('structure')}": c.get("structure")
                for c in contacts}
    return {f"{i.get('name')}-{s.get('name')}": s.get("name")
            for i in case.get("ice", []) for s in case.get("structure", [])}


def load_split(results: dict, contacts: dict[str, dict]) -> dict:
    """Per structure, its contact pairs' total impulse (N s, magnitude of the time integral of
    the force) and share, main pair (largest impulse) first."""
    pairs = pair_structures(results.get("meta", {}).get("case", ""))
    out: dict[str, Any] = {}
    for name, h in contacts.items():
        t, f = h["time"], h["force"]
        impulse = float(np.linalg.norm(np.trapezoid(f, t, axis=0))) if t.size > 1 else 0.0
        out.setdefault(pairs.get(name, "?"), {})[name] = impulse
    split = {}
    for structure, by_pair in out.items():
        total = sum(by_pair.values()) or 1.0
        ranked = sorted(by_pair.items(), key=lambda kv: -kv[1])
        split[structure] = {"main": ranked[0][0],
                            "pairs": {k: {"impulse": v, "share": v / total} for k, v in ranked},
                            "note": "split by contact pair (one per ice body); fragments of one "
                                    "body stay in its pair: see the filtered residual"}
    return split
