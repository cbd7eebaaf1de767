"""Edge crushing of a level-ice sheet against a rigid wall (``ice_edge_crushing.toml``): the
"ice" failure law gives a crushing regime, not a sheet that shatters or rebounds.

Checked over the run (5 cm of penetration at 0.1 m/s; ``--quick``: at 0.5 m/s):

- ``edge_crushing_load``: the fraction of the time after first contact in which the wall's
  load is zero. Issue 14: at most 10 % (a crushing regime carries load throughout; a sheet that
  shatters or rebounds leaves the wall unloaded).
- ``edge_crushing_far_field``: the largest damage of the ice that is, at the end, farther than
  two thicknesses (0.4 m) from the wall: the ice away from the contact stays intact (0).
- ``edge_crushing_pressure``: the mean load over the nominal contact area (thickness x the
  wedge's width at the penetration, :func:`nominal_pressure`) in units of the compressive
  strength: 0.5 to 2.5 (issue 14), i.e. 1.5 +- 1. Korzhavin's (1962) formula for the crushing
  pressure of level ice on a vertical structure, p = I k m sigma_c, has an indentation factor
  I = 1-3 (confinement), a contact factor k = 0.4-0.7 (non-simultaneous contact) and a shape
  factor m = 0.85-1 (ISO 19906:2019 A.8.2.4.3 has the same form): their product spans about
  0.3-2.5. The crushed ice's friction (``crushed_friction`` = 0.58 in the case,
  :mod:`pdfem.pd.failure.crushed_shear`) holds the crushed layer in the contact; without it the layer
  is squeezed out at 0.27-0.37 sigma_c (docs/ice_failure.md).

Measured: see docs/ice_failure.md (``pdfem validate --case edge_crushing_load --case
edge_crushing_far_field --case edge_crushing_pressure [--quick]``). SI units (m, s, N).
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

from pdfem.case import Case
from pdfem.validation.case import Outcome, ValidationCase, replace_ice, replace_run

if TYPE_CHECKING:
    from matplotlib.figure import Figure

THICKNESS = 0.2
"""The sheet's thickness (m)."""

WALL = 0.02
"""The wall plane x (m): the tip's first particle layer."""

FLANK = 30.0
"""The angle of the wedge's flanks to the wall (deg), ``ice_sheet_wedge.obj``."""


def _load(outcome: Outcome) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) and the force pressing on the wall (N, positive)."""
    h = outcome.data["histories"]["loads/wall"]
    return h["time"], -h["force"][:, 0]


def zero_load_fraction(outcome: Outcome) -> float:
    """Fraction of the coupling steps after the first contact with no load on the wall (-)."""
    _, force = _load(outcome)
    loaded = np.flatnonzero(force > 0.0)
    if len(loaded) == 0:
        return 1.0
    return float(np.mean(force[loaded[0]:] <= 0.0))


def far_field_damage(outcome: Outcome) -> float:
    """The largest damage (-) of the particles farther than two thicknesses from the wall at
    the end of the run (current positions: the sheet has moved 5 cm towards the wall)."""
    body = outcome.data["ice"]["sheet"]
    far = body["x0"][:, 0] + body["u"][-1][:, 0] > WALL + 2 * THICKNESS
    return float(body["damage"][-1][far].max())


def nominal_pressure(outcome: Outcome) -> float:
    """Mean over the time after first contact of the wall load over the nominal contact area,
    in units of ``compressive_strength`` (-): area = thickness x the wedge's width at the
    penetration, the push's displacement plus half a particle spacing (the tip cell), width =
    2 penetration / tan(20 deg) (at most the sheet's 1 m)."""
    t, force = _load(outcome)
    ice = outcome.case.ice[0]
    bc = ice.prescribed_velocity[0]
    speed = abs(bc.velocity[0])
    ramp = bc.ramp_time
    push = np.where(t < ramp, 0.5 * speed * t * t / max(ramp, 1e-30), speed * (t - 0.5 * ramp))
    width = np.minimum(2.0 * (push + 0.5 * ice.dx) / np.tan(np.radians(FLANK)), 1.0)
    loaded = np.flatnonzero(force > 0.0)
    if len(loaded) == 0:
        return 0.0
    p = force[loaded[0]:] / (THICKNESS * width[loaded[0]:])
    return float(np.mean(p) / ice.material.compressive_strength)


def plot(fig: Figure, outcome: Outcome, value: float, ref: float) -> None:
    """The wall's load history."""
    t, force = _load(outcome)
    ax = fig.add_subplot()
    ax.plot(t, force / 1e3, lw=0.8)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("ice load on the wall [kN]")
    ax.set_title(f"mean pressure on the nominal contact area: {nominal_pressure(outcome):.2f} "
                 "compressive_strength", fontsize=9)


def _quick(case: Case) -> Case:
    """The same 5 cm of penetration, pushed (far end and sides) at 0.5 m/s (0.1 s)."""
    fast = tuple(dataclasses.replace(bc, velocity=(-0.5, 0.0, 0.0))
                 for bc in case.ice[0].prescribed_velocity)
    case = replace_ice(case, prescribed_velocity=fast)
    return replace_run(case, end_time=0.1, output_interval=0.005)


_COMMON = dict(case_file="ice_edge_crushing.toml", relative=False, plot=plot, quick=_quick,
               quick_note="pushed at 0.5 m/s instead of 0.1 m/s (the same 5 cm, 0.1 s)")
CASES = (
    ValidationCase(
        name="edge_crushing_load", quantity="time at zero wall load after first contact",
        unit="-", measure=zero_load_fraction, reference=lambda case: 0.0, tolerance=0.10,
        source="issue 14: in a crushing regime the load never stays at zero for more than "
               "10 % of the time after first contact", **_COMMON),
    ValidationCase(
        name="edge_crushing_far_field", quantity="damage beyond two thicknesses from the wall",
        unit="-", measure=far_field_damage, reference=lambda case: 0.0, tolerance=0.05,
        source="issue 14: the ice farther than two thicknesses from the wall stays intact",
        **_COMMON),
    ValidationCase(
        name="edge_crushing_pressure",
        quantity="mean wall load over the nominal contact area / compressive_strength",
        unit="-", measure=nominal_pressure, reference=lambda case: 1.5, tolerance=1.0,
        source="issue 14's band 0.5-2.5 sigma_c: Korzhavin (1962) p = I k m sigma_c with "
               "I = 1-3, k = 0.4-0.7, m = 0.85-1; ISO 19906:2019 A.8.2.4.3", **_COMMON),
)
