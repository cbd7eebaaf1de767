"""Flexural strength of an ice beam in three- and four-point bending (``ice_beam_*bending*.toml``
of ``models/validation/``), at the case's spacing dx and at dx/2.

The beam rests on fixed lines of particles (the supports) and is pushed down by prescribed
velocity regions (the loading noses). The load F (N) is the reaction of the noses: the force
they exert on the beam, ``sum over nose particles of (rho a_prescribed - f) V`` (the prescribed
particles move as told, so whatever the bonds pull on them the nose supplies). :func:`pull`
steps the ice body built from the case (:func:`pdfem.run.build_ice.build_ice_body`) and
records that reaction every few steps; the case's ``end_time`` bounds the run, which stops
early once the beam has broken (the load fell below a third of its peak). The flexural strength
is the beam formula at the peak load (ASTM C78 / ITTC 7.5-02-04-02):

    three-point:  sigma_f = 3 F L / (2 b h^2)
    four-point:   sigma_f = 3 F (L - L_i) / (2 b h^2)    (= F L / (b h^2) for L_i = L / 3)

with L the support span, L_i the loading span (between the two noses), b the width, h the
depth, F the total load. Supports and noses are read from the case: their regions' centres.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from pdfem.case import Case
from pdfem.geometry.shapes import Box
from pdfem.run.build_ice import build_ice_body
from pdfem.validation.case import Outcome, ValidationCase

#: The run stops once the load has fallen below this fraction of its peak (the beam broke).
BROKEN = 1.0 / 3.0


def pull(case: Case, directory: Path) -> dict:
    """Step the first ice body of ``case`` and record the load of its prescribed regions.

    Returns
    -------
    dict
        ``time`` (s), ``force`` (N, (n,3): the total force the prescribed-velocity regions
        exert on the body), ``broken`` (bonds broken so far) at every record; ``dx`` (m).
    """
    cfg = case.ice[0]
    body = build_ice_body(cfg, case.run, case.file)
    rho = body.material.density
    dt = case.run.safety_factor * body.stable_time_step()
    steps = max(1, math.ceil(case.run.end_time / dt))
    every = max(1, steps // 2000)
    body.start()
    times, forces, broken = [], [], []
    peak, nbroken = 0.0, 0
    for k in range(1, steps + 1):
        nbroken += body.step(dt)
        if k % every:
            continue
        total = np.zeros(3)
        for c in body.constraints:
            total += ((rho * c.acceleration(body.time) - body.f[c.index]) * body.vol[c.index, None]).sum(axis=0)
        times.append(body.time)
        forces.append(total)
        broken.append(nbroken)
        load = float(np.linalg.norm(total))
        peak = max(peak, load)
        if nbroken and load < BROKEN * peak:
            break
    return {"time": np.array(times), "force": np.array(forces), "broken": np.array(broken),
            "dx": cfg.dx}


def _centre(shape) -> np.ndarray:
    lo, hi = shape.bounds()
    return 0.5 * (np.asarray(lo) + np.asarray(hi))


def beam_geometry(case: Case) -> dict:
    """Support span L, loading span L_i (0: three-point), width b and depth h (m) of the beam."""
    cfg = case.ice[0]
    lo, hi = cfg.shape.bounds()
    supports = sorted(_centre(shape)[0] for shape, _ in cfg.fixed)
    noses = sorted(_centre(bc.region)[0] for bc in cfg.prescribed_velocity)
    return {"L": supports[-1] - supports[0], "Li": noses[-1] - noses[0],
            "b": float(hi[1] - lo[1]), "h": float(hi[2] - lo[2])}


def flexural_strength(case: Case, load: float) -> float:
    """sigma_f = 3 F (L - L_i) / (2 b h^2) (Pa) for a total load F (N); L_i = 0: three-point."""
    g = beam_geometry(case)
    return 3.0 * load * (g["L"] - g["Li"]) / (2.0 * g["b"] * g["h"] ** 2)


def peak_load(data: dict) -> float:
    """The largest downward load (N) of a :func:`pull` record."""
    return float(np.max(-data["force"][:, 2]))
