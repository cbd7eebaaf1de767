"""Lindqvist's (1989) level-ice resistance of a ship: the published reference of the
icebreaking case (docs/icebreaking.md). SI units: m, rad, Pa, N, kg/m^3, m/s.

Lindqvist, G. (1989), "A straightforward method for calculation of ice resistance of ships",
Proc. POAC'89, Luleå, vol. 2, pp. 722-735. With the stem angle phi (from the horizontal), the
waterline entrance half angle alpha, psi = arctan(tan phi / sin alpha) (the normal angle of the
bow at the stem), the ice thickness h, its bending strength sigma_b, Young's modulus E,
Poisson's ratio nu, the densities rho_w, rho_i and the ice-hull friction coefficient mu::

    R_c = 0.5 sigma_b h^2 (tan phi + mu cos phi / cos psi) / (1 - mu sin phi / cos psi)
    R_b = 27/64 sigma_b B h^1.5 / sqrt(E / (12 (1 - nu^2) g rho_w))
          (tan psi + mu cos phi / (sin alpha cos psi)) (1 + 1 / cos psi)
    R_s = (rho_w - rho_i) g h B (T (B + T) / (B + 2 T)
          + mu (0.7 L - T / tan phi - B / (4 tan alpha)
                + T cos phi cos psi sqrt(1 / sin^2 phi + 1 / tan^2 alpha)))
    R_ice = (R_c + R_b) (1 + 1.4 v / sqrt(g h)) + R_s (1 + 9.4 v / sqrt(g L))

crushing at the stem (R_c), bending of the sheet by the bow (R_b, the 27/64 and the
characteristic length of a plate on an elastic foundation), submersion of the broken pieces
under the hull (R_s: buoyancy and the friction it causes along 0.7 L of the hull), with the
speed corrections fitted to full-scale Baltic trials.
"""

from __future__ import annotations

import math

GRAVITY = 9.81
"""Gravitational acceleration (m/s^2) used by the formula."""


def lindqvist_resistance(*, length: float, beam: float, draught: float, stem_angle: float,
                         entrance_angle: float, thickness: float, bending_strength: float,
                         youngs_modulus: float, speed: float, friction: float = 0.1,
                         poisson_ratio: float = 0.3, water_density: float = 1025.0,
                         ice_density: float = 900.0) -> dict[str, float]:
    """Level-ice resistance of a ship by Lindqvist (1989) and its three parts (SI).

    Parameters
    ----------
    length, beam, draught
        Waterline length L, beam B and draught T (m): ``length``, ``beam``, ``draught`` of
        ``models/icebreaker.py``.
    stem_angle, entrance_angle
        Stem angle phi from the horizontal and waterline entrance half angle alpha (rad):
        ``stem_angle`` and ``entrance_angle`` of ``models/icebreaker.py``.
    thickness
        Ice thickness h (m).
    bending_strength
        Flexural (bending) strength sigma_b of the ice (Pa).
    youngs_modulus
        Young's modulus E of the ice (Pa).
    speed
        Ship speed v (m/s).
    friction
        Ice-hull friction coefficient mu (-).
    poisson_ratio
        Poisson's ratio nu of the ice (-).
    water_density, ice_density
        rho_w, rho_i (kg/m^3).

    Returns
    -------
    dict
        ``crushing``, ``bending``, ``submersion`` (N, the speed-independent parts R_c, R_b,
        R_s), ``psi`` (rad), ``total`` (N, R_ice at the speed) and ``breaking`` (N, the
        icebreaking part (R_c + R_b)(1 + 1.4 v / sqrt(g h)) alone).
    """
    g, phi, alpha, mu = GRAVITY, stem_angle, entrance_angle, friction
    L, B, T, h = length, beam, draught, thickness
    psi = math.atan(math.tan(phi) / math.sin(alpha))
    r_c = (0.5 * bending_strength * h ** 2 * (math.tan(phi) + mu * math.cos(phi) / math.cos(psi))
           / (1.0 - mu * math.sin(phi) / math.cos(psi)))
    r_b = (27.0 / 64.0 * bending_strength * B * h ** 1.5
           / math.sqrt(youngs_modulus / (12.0 * (1.0 - poisson_ratio ** 2) * g * water_density))
           * (math.tan(psi) + mu * math.cos(phi) / (math.sin(alpha) * math.cos(psi)))
           * (1.0 + 1.0 / math.cos(psi)))
    r_s = ((water_density - ice_density) * g * h * B
           * (T * (B + T) / (B + 2.0 * T)
              + mu * (0.7 * L - T / math.tan(phi) - B / (4.0 * math.tan(alpha))
                      + T * math.cos(phi) * math.cos(psi)
                      * math.sqrt(1.0 / math.sin(phi) ** 2 + 1.0 / math.tan(alpha) ** 2))))
    breaking = (r_c + r_b) * (1.0 + 1.4 * speed / math.sqrt(g * h))
    total = breaking + r_s * (1.0 + 9.4 * speed / math.sqrt(g * L))
    return {"crushing": r_c, "bending": r_b, "submersion": r_s, "psi": psi,
            "breaking": breaking, "total": total}
