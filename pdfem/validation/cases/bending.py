"""Flexural strength of an ice beam in three- and four-point bending
(``ice_beam_bending_three_point.toml``, ``ice_beam_bending_four_point.toml``), at the case's
spacing dx and at dx/2, against the input ``flexural_strength``.

The beam hangs on hinges (one held row of particles each) and is pushed down by loading noses
(prescribed-velocity regions). The load F (N) is the nose reaction, the force the noses exert
on the beam: ``sum over nose particles of (rho a_prescribed - f) V`` (a prescribed particle
moves as told, so the nose supplies whatever the bonds pull on it). :func:`pull` steps the ice
body built from the case (:func:`pdfem.run.build_ice.build_ice_body`) and records it; the run
stops soon after the beam has failed. The flexural strength is the beam formula at the failure
load (ASTM C78; ITTC 7.5-02-04-02):

    three-point:  sigma_f = 3 F L / (2 b h^2)
    four-point:   sigma_f = 3 F (L - L_i) / (2 b h^2)    (= F L / (b h^2) for L_i = L / 3)

with L the support span, L_i the loading span, b the width, h the depth (m), spans measured
between the particle rows the regions select. The failure load is the peak before the first
drop of the load (:func:`failure_load`): under the constant moment of four-point bending the
perfect lattice breaks its whole bottom layer at once, after which the shallower beam rings and
is loaded on (docs/ice_strength.md).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pdfem.case import Case
from pdfem.geometry.lattice import fill
from pdfem.geometry.shapes import Box
from pdfem.run.build_ice import build_ice_body
from pdfem.validation.case import Outcome, ValidationCase, replace_ice

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: A drop of the load by this fraction of its running peak, once bonds broke, is failure.
DROP = 0.1
#: Time (s) the run goes on after failure (for the plot), unless the load has gone first.
AFTER = 0.5e-3


def failure_load(force: np.ndarray, broken: np.ndarray) -> float:
    """The failure load (N): the running peak of the load when it first falls by :data:`DROP`
    below that peak while bonds have broken since the peak was reached (a drop without breaking
    is ringing, not failure); the overall peak if that never happens.

    Parameters
    ----------
    force
        (n,) loads (N) at the records.
    broken
        (n,) bonds broken so far at the records.
    """
    index = np.arange(force.size)
    at_peak = np.maximum.accumulate(np.where(force >= np.maximum.accumulate(force), index, 0))
    peak = force[at_peak]
    failed = np.flatnonzero((force < (1.0 - DROP) * peak) & (broken > broken[at_peak]))
    return float(peak[failed[0]] if failed.size else force.max())


def pull(case: Case, directory: Path | None = None) -> dict:
    """Step the first ice body of ``case`` and record the load of its prescribed regions.

    Parameters
    ----------
    case
        A case whose first ice body has ``prescribed_velocity`` regions (the load).
    directory
        Unused (nothing is written); the validation executor signature.

    Returns
    -------
    dict
        ``time`` (s), ``force`` (N, (n,3): the total force the prescribed-velocity regions
        exert on the body, the sum of their reactions :meth:`pdfem.pd.body.IceBody.reactions`,
        which a run writes as ``loads/<body>.<name>/force``), ``broken`` (bonds broken so far) at every record; ``geometry``
        (:func:`beam_geometry`) and ``dx`` (m) of the case as run.
    """
    cfg = case.ice[0]
    body = build_ice_body(cfg, case.run, case.file)
    drivers = [bc.name for bc in cfg.prescribed_velocity]
    dt = case.run.safety_factor * body.stable_time_step()
    steps = max(1, math.ceil(case.run.end_time / dt))
    every = max(1, steps // 4000)
    body.start()
    times, forces, broken = [], [], []
    peak, nbroken, broken_at_peak, failed_at = 0.0, 0, 0, math.inf
    for k in range(1, steps + 1):
        nbroken += body.step(dt)
        if k % every:
            continue
        reactions = body.reactions()
        total = np.sum([reactions[name] for name in drivers], axis=0)
        times.append(body.time)
        forces.append(total)
        broken.append(nbroken)
        load = float(np.linalg.norm(total))
        if load >= peak:
            peak, broken_at_peak = load, nbroken
        if nbroken > broken_at_peak and load < (1.0 - DROP) * peak:
            failed_at = min(failed_at, body.time)
        if body.time > failed_at + AFTER or (nbroken and load < 0.2 * peak):
            break
    return {"time": np.array(times), "force": np.array(forces), "broken": np.array(broken),
            "geometry": beam_geometry(case), "dx": cfg.dx}


def beam_geometry(case: Case) -> dict:
    """Where the first ice body of ``case`` is held and loaded (m).

    Returns
    -------
    dict
        ``supports`` and ``noses``: mean x of the particles each ``fixed`` and
        ``prescribed_velocity`` region selects (the lattice rows, not the nominal positions),
        sorted; ``b`` the width (y extent) and ``h`` the depth (z extent) of the beam.
    """
    cfg = case.ice[0]
    x = fill(cfg.shape, cfg.dx)
    lo, hi = cfg.shape.bounds()
    supports = sorted(float(x[fx.region.contains(x), 0].mean()) for fx in cfg.fixed)
    noses = sorted(float(x[bc.region.contains(x), 0].mean()) for bc in cfg.prescribed_velocity)
    return {"supports": supports, "noses": noses, "b": float(hi[1] - lo[1]),
            "h": float(hi[2] - lo[2])}


def flexural_strength(geometry: dict, load: float) -> float:
    """The beam formula sigma_f = 6 M / (b h^2) (Pa) at the total load ``load`` F (N).

    One nose at x_n between supports x_1, x_2 (span L): M = F (x_n - x_1) (x_2 - x_n) / L,
    F L / 4 at mid-span, so sigma_f = 3 F L / (2 b h^2). Two noses (symmetric four-point):
    M = (F / 2) (L - L_i) / 2, so sigma_f = 3 F (L - L_i) / (2 b h^2). ``geometry`` is
    :func:`beam_geometry`'s.
    """
    (x1, x2), noses = geometry["supports"], geometry["noses"]
    if len(noses) == 1:
        moment = load * (noses[0] - x1) * (x2 - noses[0]) / (x2 - x1)
    else:
        moment = 0.25 * load * ((x2 - x1) - (noses[-1] - noses[0]))
    return 6.0 * moment / (geometry["b"] * geometry["h"] ** 2)


def measure(outcome: Outcome) -> float:
    """Flexural strength (Pa): the beam formula at the failure load of the nose reaction."""
    d = outcome.data
    return flexural_strength(d["geometry"], failure_load(-d["force"][:, 2], d["broken"]))


def reference(case: Case) -> float:
    """The input flexural strength (Pa)."""
    return case.ice[0].material.flexural_strength


def halved(case: Case) -> Case:
    """The case with dx and the horizon halved (the regions select the matching rows)."""
    cfg = case.ice[0]
    return replace_ice(case, dx=0.5 * cfg.dx, horizon=0.5 * cfg.horizon)


def pull_halved(case: Case, directory: Path | None = None) -> dict:
    """:func:`pull` of the case at dx/2."""
    return pull(halved(case), directory)


QUICK_SPACINGS = 4
"""Lattice spacings across the ``--quick`` beam's width. Four is the fewest that keep the
flexural strength: at dx = 0.01 m the four-point beam gives 0.688 MPa 0.04 m wide and 1.215
MPa 0.02 m wide (two spacings); at dx/2, 0.676 MPa 0.04 m wide (eight) and 0.689 MPa 0.02 m
wide (four); three-point 0.750 and 0.756 MPa (2026-11-29)."""


def _narrowed(case: Case, width: float) -> Case:
    lo, hi = case.ice[0].shape.bounds()
    return replace_ice(case, shape=Box(tuple(lo), (hi[0], lo[1] + width, hi[2])))


def quick(case: Case) -> Case:
    """The ``--quick`` test: the beam :data:`QUICK_SPACINGS` lattice spacings wide (0.04 m)
    instead of 0.10 m (hinges and noses span the width, so they follow); the depth, the spans
    and the loading are unchanged."""
    return _narrowed(case, QUICK_SPACINGS * case.ice[0].dx)


def quick_halved(case: Case) -> Case:
    """The ``--quick`` test of the dx/2 entries: as :func:`quick`, the same number of lattice
    spacings across at dx/2 (0.02 m), so that the two levels differ by the refinement only."""
    return _narrowed(case, QUICK_SPACINGS * 0.5 * case.ice[0].dx)


def plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """The beam-formula stress of the nose load against time, and the input strength."""
    d = outcome.data
    sigma = np.array([flexural_strength(d["geometry"], f) for f in -d["force"][:, 2]])
    ax = fig.add_subplot()
    ax.plot(d["time"] * 1e3, sigma / 1e6, "-", label="pdfem: 6 M(F) / (b h^2)")
    ax.axhline(ref / 1e6, color="k", ls="--", label="input flexural strength")
    ax.axhline(value / 1e6, color="r", ls=":", label=f"at failure ({value / 1e6:.3f} MPa)")
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("beam-formula stress [MPa]")
    ax.legend()


_SOURCE = ("beam formula at the failure load, sigma_f = 3 F (L - L_i) / (2 b h^2) (ASTM C78; "
           "ITTC 7.5-02-04-02); input flexural strength 0.7 MPa, first-year sea ice "
           "(Timco & O'Brien 1994, Cold Reg. Sci. Technol. 22)")
CASES = tuple(
    ValidationCase(
        name=f"flexural_strength_{kind}{suffix}", case_file=f"ice_beam_bending_{kind}.toml",
        quantity=f"flexural strength, {kind.replace('_', '-')} bending{words}", unit="Pa",
        measure=measure, reference=reference, source=_SOURCE, tolerance=0.10, quick=quick_fn,
        quick_note=f"beam {QUICK_SPACINGS} lattice spacings ({width}) wide instead of 0.10 m",
        execute=execute, plot=plot)
    for kind in ("three_point", "four_point")
    for suffix, words, execute, quick_fn, width in (
        ("", ", dx", pull, quick, "0.04 m"),
        ("_half_dx", ", dx/2", pull_halved, quick_halved, "0.02 m"))
)
