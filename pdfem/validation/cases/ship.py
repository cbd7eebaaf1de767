"""Free 6-DOF ship hull in calm water (``ship_rest.toml``, ``ship_heave.toml``,
``ship_pitch.toml``): no drift at rest, and the heave and pitch natural periods against the
hydrostatic estimates (:class:`pdfem.motion.ship.Ship`, docs/ship.md). SI units.

Measured from the ship's motion history (``motions/<name>``, every coupling step): the drift is
the largest distance of the centre of gravity from its start (m, absolute tolerance 1 mm); a
period is twice the mean spacing of the crossings of the heave (z of G) or the pitch angle
(y component of the rotation vector) through the middle of its swing.

References, from the parametric hull surface (:func:`pdfem.models.icebreaker
.hydrostatic_properties`: exact in x, a fine midpoint rule in z), independent of the hull mesh
and of the hydrostatics under test: heave ``T = 2 pi sqrt(m / (rho g A_wp))``, pitch
``T = 2 pi sqrt(I_yy / (rho g V GM_L))`` with ``GM_L = z_B - z_G + I_L / V`` and
``I_yy = m k_y^2`` (e.g. Newman, Marine Hydrodynamics, 1977, sec. 6.16, added mass zero).
``m`` is the case's mass or ``rho V``.

Measured (``pdfem validate --case ship_rest_drift --case ship_heave_period --case
ship_pitch_period``): drift 2.8e-5 m over 10 s; heave period 0.897138 s against 0.897140 s
(-0.0002 %); pitch period 1.01725 s against 1.01726 s (-0.0015 %); ``--quick`` (2 s, 2 s,
2.2 s) the same periods.
"""

from __future__ import annotations

import math

import numpy as np

from pdfem.case import Case
from pdfem.models.icebreaker import hydrostatic_properties
from pdfem.validation.case import Outcome, ValidationCase, replace_run
from pdfem.validation.measure import zero_crossings


def _motion(outcome: Outcome) -> dict:
    return outcome.data["histories"][f"motions/{outcome.case.structures[0].name}"]


def drift(outcome: Outcome) -> float:
    """Largest distance (m) of the centre of gravity from its position at the start."""
    x = _motion(outcome)["position"]
    return float(np.linalg.norm(x - x[0], axis=1).max())


def _period(t: np.ndarray, w: np.ndarray) -> float:
    crossings = zero_crossings(t, w - 0.5 * (w.max() + w.min()))
    if len(crossings) < 3:
        raise ValueError(f"the hull crossed the middle of its swing {len(crossings)} times; "
                         "need 3")
    return float(2.0 * (crossings[-1] - crossings[0]) / (len(crossings) - 1))


def heave_period(outcome: Outcome) -> float:
    """Period (s) of the heave of the centre of gravity."""
    m = _motion(outcome)
    return _period(m["time"], m["position"][:, 2])


def pitch_period(outcome: Outcome) -> float:
    """Period (s) of the pitch angle."""
    m = _motion(outcome)
    return _period(m["time"], m["rotation"][:, 1])


def _hydrostatics(case: Case) -> tuple[dict, float, float, float]:
    """Parametric hydrostatics, mass (kg), water density (kg/m^3), g (m/s^2)."""
    s = case.structures[0]
    h = hydrostatic_properties(**s.params)
    rho, g = case.water.density, -case.run.gravity[2]
    mass = s.ship.section.mass or rho * h["volume"]
    return h, mass, rho, g


def heave_reference(case: Case) -> float:
    """T = 2 pi sqrt(m / (rho g A_wp)) (s)."""
    h, m, rho, g = _hydrostatics(case)
    return 2.0 * math.pi * math.sqrt(m / (rho * g * h["waterplane_area"]))


def pitch_reference(case: Case) -> float:
    """T = 2 pi sqrt(I_yy / (rho g V GM_L)) (s), GM_L = z_B - z_G + I_L / V (G on the water
    surface unless the case gives it)."""
    h, m, rho, g = _hydrostatics(case)
    ship = case.structures[0].ship
    cg = ship.section.center_of_gravity
    z_g = ship.water_level if cg is None else cg[2]
    gm = h["z_b"] - z_g + h["i_l"] / h["volume"]
    i_yy = m * ship.section.radii_of_gyration[1] ** 2
    return 2.0 * math.pi * math.sqrt(i_yy / (rho * g * h["volume"] * gm))


def _zero(case: Case) -> float:
    return 0.0


def _shorter(end_time: float):
    def quick(case: Case) -> Case:
        return replace_run(case, end_time=end_time)
    quick.__doc__ = f"Run to {end_time:g} s."
    return quick


CASES = (
    ValidationCase(
        name="ship_rest_drift", case_file="ship_rest.toml",
        quantity="drift of a free hull at rest in calm water over 10 s", unit="m",
        measure=drift, reference=_zero, quick=_shorter(2.0), tolerance=1e-3, relative=False,
        source="hydrostatic equilibrium: a hull at rest at its equilibrium stays there "
               "(issue 15: less than 1 mm over 10 s)",
        quick_note="run to 2 s instead of 10 s"),
    ValidationCase(
        name="ship_heave_period", case_file="ship_heave.toml",
        quantity="free heave period of a floating hull", unit="s",
        measure=heave_period, reference=heave_reference, quick=_shorter(2.0), tolerance=0.05,
        source="mass m on the hydrostatic spring rho g A_wp, no added mass: "
               "T = 2 pi sqrt(m / (rho g A_wp)) (Newman, Marine Hydrodynamics, 1977, sec. "
               "6.16), A_wp from the parametric hull",
        quick_note="run to 2 s (two periods) instead of 4.5 s"),
    ValidationCase(
        name="ship_pitch_period", case_file="ship_pitch.toml",
        quantity="free pitch period of a floating hull", unit="s",
        measure=pitch_period, reference=pitch_reference, quick=_shorter(2.2), tolerance=0.05,
        source="T = 2 pi sqrt(I_yy / (rho g V GM_L)), GM_L = z_B - z_G + I_L / V (Newman, "
               "Marine Hydrodynamics, 1977, sec. 6.16), V, z_B, I_L from the parametric hull",
        quick_note="run to 2.2 s (two periods) instead of 5 s"),
)
