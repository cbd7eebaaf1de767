"""Global crushing pressure of level ice on a vertical structure by the two engineering formulas
the edge-crushing case (docs/ice_failure.md) is compared with. SI units: m, Pa.

**Korzhavin** (1962), in the form of IEC 61400-3 Ed. 1 (2009), Annex E, as implemented in the
IceFloe module of OpenFAST (DNV KEMA Renewables 2014, module ``iceCrushingIEC``, "crushing on
vertical surfaces by IEC/Korzhavin method")::

    F = k1 k2 k3 h D sigma_c,    k3 = sqrt(1 + 5 h / D)

with h the ice thickness, D the structure's width, sigma_c the uniaxial compressive strength of
the ice, k1 a shape factor and k2 a contact factor (each accepted in 0.1-1 by IceFloe; its IEC
test case, ``modules/icefloe/test/GLA_proto_lockin_IEC.log``, takes k1 = 0.9 and k2 = 0.5 and
gives F = 7.00036 MN for h = 1 m, D = 5 m, sigma_c = 2.2 MPa) and k3 the indentation
(aspect-ratio) factor: the confinement of the contact zone by the ice around it. F is the
design (maximum) load; IceFloe's IEC load history around it (IEC 61400-3 Annex E, E.4.6:
``IECLoadTimeSeries`` in ``IceFloeBase.F90``) is F (0.75 + 0.25 sin 2 pi f t), so the load
cycles between 0.5 F and F about a mean of 0.75 F. The recommended values of k1 and k2 in the
standard itself, and Korzhavin's own tables, were not reachable here.

**ISO 19906** (2010), A.8.2.4.3.3, as implemented in IceFloe (module ``iceCrushingISO``)::

    p_G = C_R (h / h1)^n (w / h)^m,   h1 = 1 m,  m = -0.16,  n = -0.5 + h / 5 (h < 1 m), -0.3

with w the structure's width and C_R an empirical ice strength coefficient fitted to measured
global loads (not sigma_c: the two formulas do not have the same form). IceFloe's ISO test case
(``GLA_proto_randomCrush_ISO.log``) gives 8.50271 MN for h = 1 m, w = 5 m and C_R = 2.2 MPa.
The values of C_R that ISO 19906 gives for the Arctic and the Baltic were not reachable here.
"""

from __future__ import annotations

import numpy as np

IEC_SHAPE_FACTOR = 0.9
"""k1 of IceFloe's IEC 61400-3 test case (``GLA_proto_lockin_IEC.log``)."""

IEC_CONTACT_FACTOR = 0.5
"""k2 of IceFloe's IEC 61400-3 test case (``GLA_proto_lockin_IEC.log``)."""

IEC_MEAN_FRACTION = 0.75
"""Mean of the IEC 61400-3 (Annex E, E.4.6) load cycle, F (0.75 + 0.25 sin 2 pi f t), over F."""


def indentation_factor(thickness, width):
    """Korzhavin's indentation factor k3 = sqrt(1 + 5 h / D) (-) for ice ``thickness`` h and
    structure ``width`` D (m; arrays broadcast)."""
    return np.sqrt(1.0 + 5.0 * np.asarray(thickness, float) / np.asarray(width, float))


def korzhavin_force(thickness: float, width: float, strength: float,
                    shape_factor: float = IEC_SHAPE_FACTOR,
                    contact_factor: float = IEC_CONTACT_FACTOR) -> float:
    """Design crushing load F = k1 k2 k3 h D sigma_c (N) of Korzhavin's formula (IEC 61400-3
    Annex E).

    Parameters
    ----------
    thickness, width
        Ice thickness h and structure width D (m).
    strength
        Uniaxial compressive strength sigma_c of the ice (Pa).
    shape_factor, contact_factor
        k1 and k2 (-); defaults: IceFloe's IEC test case, 0.9 and 0.5.
    """
    k3 = float(indentation_factor(thickness, width))
    return shape_factor * contact_factor * k3 * thickness * width * strength


def iso_exponent_n(thickness: float) -> float:
    """ISO 19906 (2010) A.8.2.4.3.3 thickness exponent n = -0.5 + h / 5 for h < 1 m, -0.3 for
    h >= 1 m (``thickness`` h in m)."""
    return min(-0.3, 0.2 * thickness - 0.5)


def iso_pressure_factor(thickness, width, reference_thickness: float = 1.0,
                        width_exponent: float = -0.16):
    """p_G / C_R = (h / h1)^n (w / h)^m (-) of ISO 19906 (2010) A.8.2.4.3.3 for ice
    ``thickness`` h and structure ``width`` w (m; ``width`` may be an array)."""
    h = float(thickness)
    w = np.asarray(width, float)
    return (h / reference_thickness) ** iso_exponent_n(h) * (w / h) ** width_exponent


def iso_global_force(thickness: float, width: float, c_r: float) -> float:
    """Global crushing load p_G w h (N) of ISO 19906 (2010) A.8.2.4.3.3 with the ice strength
    coefficient ``c_r`` (Pa), ice ``thickness`` and structure ``width`` (m)."""
    return c_r * float(iso_pressure_factor(thickness, width)) * width * thickness
