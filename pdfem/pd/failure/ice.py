"""The ice failure law: tension, and compressive-shear crushing with a pressure dependence.

Ice against a structure fails mostly by crushing: compressive-shear faulting and pulverisation
near the contact, at a pressure of the order of the uniaxial compressive strength sigma_c,
three to ten times the tensile strength sigma_t. The critical-stretch law
(:mod:`pdfem.pd.failure.critical_stretch`) only breaks bonds in tension, so ice under a
structure pulverises only through the Poisson expansion's lateral stretch, at a "compressive
strength" set by sigma_t / nu rather than by the ice's own.

This law bounds each bond's normal stress. For a bond with direction n in a locally homogeneous
strain field, the stretch is s = n.eps.n and the dilatation theta = tr eps, so the normal stress
on the plane normal to the bond is (Hooke, lambda = K - 2 mu / 3)::

    sigma_n = lambda theta + 2 mu s                                   (tension positive)

with theta the bond's mean dilatation (theta_i + theta_j) / 2, the nonlocal volumetric strain
that the LPS step has just computed. A bond breaks

- in tension (Rankine) when sigma_n > sigma_t;
- in compression (Mohr-Coulomb with a tension cut-off) when
  p_n - kappa max(q_n, 0) >= sigma_c,  with p_n = -sigma_n the bond's normal pressure and
  q_n = (P - p_n) / 2 the mean pressure on the two directions normal to it (P = -3 K theta,
  minus the stress trace), kappa = (1 + sin phi) / (1 - sin phi) the Coulomb slope of a
  friction angle phi: sigma_1 = sigma_c + kappa sigma_3 for a bond along the largest
  compression under a confining pressure sigma_3 >= 0. Lateral tension does not lower the
  strength below sigma_c (the Coulomb line is not extended into tension, where ice fails by
  the tension criterion instead).

Both are bounds on the stretch in theta, the form the kernels take
(:mod:`pdfem.pd.failure.base`)::

    s_max = sigma_t / (2 mu) - lambda theta / (2 mu)
    s_min = min((-sigma_c + (3 kappa K / 2 - lambda (1 + kappa / 2)) theta) / (2 mu (1 + kappa / 2)),
                (-sigma_c - lambda theta) / (2 mu))

Checks (tests/pd/test_ice_failure.py): uniaxial tension sigma breaks the axial bond at sigma_t;
uniaxial compression breaks the axial bond at sigma_c and never a lateral one (sigma_n = 0 there,
so no splitting by Poisson stretch); a confining pressure sigma_3 raises the axial strength to
sigma_c + kappa sigma_3; hydrostatic pressure breaks nothing. The strengths are the input's at
any particle spacing, because both criteria are in stresses, not in stretches scaled by the
horizon (the limits, and the implied fracture energy, are in ``docs/ice_failure.md``).

A broken bond (in either mode) gives up its strain energy as fracture dissipation
(:mod:`pdfem.pd.failure.fracture`) and becomes a crushed bond (:func:`pdfem.pd.bonds.lps_law.crushed_bond`):
a compression-only, elastic-perfectly-plastic spring with the bond's deviatoric stiffness
b = b_i + b_j, whose plastic rest length starts at min(|xi|, r + s_y |xi|) (so a bond broken in
compression goes on pushing with at most its yield force: breaking releases no stress wave)
and slides when it is compressed by more than s_y = sigma_c / E. The energy its spring starts
with and the work done while it slides are counted with the fracture dissipation. Crushed ice
is thus granular: it carries compression up to a crushing pressure and, through the compressed
bonds at every angle in a horizon, shear in proportion to the confinement (a frictional
resistance), but no tension; it is never deleted and can be squeezed out of the contact
zone. With ``crushed_friction`` > 0 (a case file's default: tan(friction_angle)) a shear spring with Coulomb slip
between the ends of a pushing crushed bond (:mod:`pdfem.pd.failure.crushed_shear`) holds the crushed
layer in the contact as a granular material's internal friction does. Pairs that were never bonded meet through the
short-range contact force
(:mod:`pdfem.forces.short_range`, switched on for a body with this law).

Strain rate (optional, off by default): ice is ductile at low strain rates, where its
compressive strength rises with the rate as sigma ~ rate^(1/n) (power-law creep, Glen's n = 3),
and brittle above a transition rate of about 1e-4 to 1e-3 /s, where the strength levels off
and then falls slowly (Schulson & Duval 2009, ch. 6 and 11; Timco & Frederking 1990 for sea
ice). With ``transition_rate`` given, ``compressive_strength`` is the strength at the
transition and the strength at a lower rate is scaled by (rate / transition_rate)^n
(``rate_exponent``, default 1/3), each particle with its own rate from the last step
(:mod:`pdfem.pd.failure.strain_rate`); above the transition it stays sigma_c. The brittle-range
decline is not modelled.

The friction angle of ice: Coulombic shear faulting of ice under confinement follows
sigma_1 = sigma_c + kappa sigma_3 with an internal friction coefficient mu_i = 0.5-0.9 (Schulson
& Duval 2009, *Creep and Fracture of Ice*, Cambridge, ch. 12), i.e. phi = atan(mu_i) = 27-42 deg;
the default 30 deg gives kappa = 3.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def coulomb_slope(friction_angle_deg: float) -> float:
    """kappa = (1 + sin phi) / (1 - sin phi) for a friction angle phi in degrees (0 <= phi < 90)."""
    s = math.sin(math.radians(friction_angle_deg))
    return (1.0 + s) / (1.0 - s)


@dataclass(frozen=True)
class IceFailure:
    """Bonds break above a tensile or below a pressure-dependent compressive normal stress.

    Parameters
    ----------
    tensile_strength, compressive_strength
        sigma_t and sigma_c (Pa, > 0).
    friction_angle
        phi (degrees, 0 <= phi < 90): the strength rises by kappa = (1 + sin phi) / (1 - sin phi)
        times the confining pressure.
    K, mu
        Bulk and shear modulus of the ice (Pa).
    """

    tensile_strength: float
    compressive_strength: float
    friction_angle: float
    K: float
    mu: float
    transition_rate: float | None = None
    rate_exponent: float = 1.0 / 3.0
    crushed_friction: float = 0.0
    name: str = "ice"
    broken_bonds_push: bool = True

    @property
    def rate_dependent(self) -> bool:
        """True with a ductile-to-brittle transition rate."""
        return self.transition_rate is not None

    def strength_factor(self, rate):
        """sigma_c(rate) / sigma_c: (rate / rate_t)^n below the transition rate rate_t
        (ductile), 1 at and above it (brittle); the rate is floored at rate_t / 1000, where
        the factor is 1000^-n (0.1 for n = 1/3). Without a transition rate: 1."""
        if self.transition_rate is None:
            return 1.0
        r = np.maximum(np.asarray(rate, dtype=np.float64), 1e-3 * self.transition_rate)
        return np.minimum(1.0, (r / self.transition_rate) ** self.rate_exponent)

    @property
    def crush_yield(self) -> float:
        """sigma_c / (2 E): crushed bonds yield at half the compressive strength's uniaxial strain."""
        return 0.5 * self.compressive_strength / self.youngs_modulus

    @property
    def crush_friction(self) -> float:
        """mu of crushed ice sliding on itself (:mod:`pdfem.pd.failure.crushed_shear`; 0: none)."""
        return self.crushed_friction

    @property
    def youngs_modulus(self) -> float:
        """E = 9 K mu / (3 K + mu) (Pa)."""
        return 9.0 * self.K * self.mu / (3.0 * self.K + self.mu)

    @classmethod
    def from_material(cls, material, delta: float) -> "IceFailure":
        """The law of an ice material (:class:`pdfem.pd.materials.lps.IceMaterial`): its
        strengths and friction angle; without a tensile strength, sigma_t = E s0(delta) (the
        critical stretch's uniaxial strength)."""
        if material.compressive_strength is None:
            raise ValueError("the ice failure law needs a compressive strength (Pa)")
        st = material.tensile_strength
        if st is None:
            st = material.youngs_modulus * material.s0(delta)
        return cls(float(st), float(material.compressive_strength),
                   float(material.friction_angle), float(material.K), float(material.mu),
                   material.transition_rate, float(material.rate_exponent),
                   float(material.crushed_friction))

    def stretch_limits(self) -> tuple[float, ...]:
        """(t0, t1, c0, c1, d0, d1) of the module doc's s_max and s_min."""
        K, mu = self.K, self.mu
        lam = K - 2.0 * mu / 3.0
        kappa = coulomb_slope(self.friction_angle)
        d = 2.0 * mu * (1.0 + 0.5 * kappa)
        sc = self.compressive_strength
        return (self.tensile_strength / (2.0 * mu), -lam / (2.0 * mu),
                -sc / d, (1.5 * kappa * K - lam * (1.0 + 0.5 * kappa)) / d,
                -sc / (2.0 * mu), -lam / (2.0 * mu))

    def describe(self) -> str:
        """``ice: tensile ... MPa, compressive ... MPa, friction angle ... deg``."""
        return (f"ice failure: tensile {self.tensile_strength / 1e6:.3g} MPa, compressive "
                f"{self.compressive_strength / 1e6:.3g} MPa, friction angle "
                f"{self.friction_angle:g} deg")
