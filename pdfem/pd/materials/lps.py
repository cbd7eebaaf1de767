"""Material constants of the linear peridynamic solid (LPS) for ice.

The ordinary state-based kernels (:mod:`pdfem.pd.bonds.kernels`) need the bulk modulus ``K`` (Pa), the
shear modulus ``mu`` (Pa) and the critical stretch ``s0`` (dimensionless) of the bond-breaking
criterion. This module derives them from engineering constants: ``s0`` from a tensile strength
(``s0 = sigma_t / E``, independent of the spacing), from the fracture energy (``s0`` scales as
horizon^-1/2) or given; ``docs/ice_strength.md`` derives the strength relations.

Sea-ice defaults (``SEA_ICE_DEFAULTS``) and their sources:

- density 900 kg/m^3 (observed range 840-940 kg/m^3 for first-year sea ice, depending on brine
  and air content; Timco & Frederking 1996, Cold Reg. Sci. Technol. 24);
- Young's modulus 4.1e9 Pa: mean of Kujala's beam tests on Baltic sea ice, range 3.2-5.4 GPa
  (the figures quoted in the pdfem design notes);
- Poisson's ratio 0.3 (the value used for sea ice throughout the ice-mechanics literature,
  e.g. Timco & Weeks 2010, Cold Reg. Sci. Technol. 60);
- fracture energy 10 J/m^2: an order of magnitude; reported values for sea ice scatter over
  roughly an order of magnitude with specimen size and loading rate (Timco & Weeks 2010);
- flexural strength 0.4-0.9 MPa (Timco & O'Brien 1994, Cold Reg. Sci. Technol. 22): a typical
  input ``flexural_strength`` of a case (:func:`tensile_from_flexural`).

All values are SI.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

SEA_ICE_DEFAULTS: dict[str, float] = {
    "density": 900.0,  # kg/m^3 (840-940)
    "youngs_modulus": 4.1e9,  # Pa (Kujala: 3.2-5.4 GPa, mean 4.1)
    "poisson_ratio": 0.3,  # -
    "fracture_energy": 10.0,  # J/m^2 (order of magnitude)
    "flexural_strength_min": 0.4e6,  # Pa
    "flexural_strength_max": 0.9e6,  # Pa
}


def lps_constants(youngs_modulus: float, poisson_ratio: float) -> tuple[float, float]:
    """Bulk and shear modulus of the 3-D linear peridynamic solid.

    Parameters
    ----------
    youngs_modulus
        Young's modulus E (Pa), > 0.
    poisson_ratio
        Poisson's ratio nu, -1 < nu < 0.5.

    Returns
    -------
    K, mu
        Bulk modulus ``E / (3 (1 - 2 nu))`` and shear modulus ``E / (2 (1 + nu))`` (Pa).

    Raises
    ------
    ValueError
        If E is not positive and finite or nu is outside (-1, 0.5).
    """
    E = float(youngs_modulus)
    nu = float(poisson_ratio)
    if not (math.isfinite(E) and E > 0.0):
        raise ValueError(f"Young's modulus must be a positive finite number of pascals, got {E!r}")
    if not (math.isfinite(nu) and -1.0 < nu < 0.5):
        raise ValueError(
            f"Poisson's ratio must lie strictly between -1 and 0.5 for a 3-D solid, got {nu!r}"
        )
    return E / (3.0 * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))


def critical_stretch(fracture_energy: float, K: float, mu: float, delta: float) -> float:
    """Critical bond stretch of 3-D ordinary state-based PD from the fracture energy.

    ``s0 = sqrt(G0 / ((3 mu + (3/4)^4 (K - 5 mu / 3)) delta))``: the energy needed to break every
    bond crossing a unit area of a crack surface equals G0 (Madenci & Oterkus 2014, *Peridynamic
    Theory and Its Applications*, Springer, the OSB critical-stretch relation for 3-D; the
    bond-based analogue is Silling & Askari 2005).

    The relation is a continuum result for the influence function w = 1. pdfem's lattice bodies
    use the cubic influence function of :mod:`pdfem.pd.bonds.influence`, whose mean over directions is
    1, so the continuum relation holds unchanged on average over crack orientations. On the
    lattice, the energy of the bonds crossing a unit area at a given stretch,
    sum over crossing bonds of omega |xi|^2 / m, is with that weight 0.967 (crack plane normal to
    a lattice axis), 0.995 ({110} plane) and 1.005 ({111} plane) times its w = 1 value at
    delta = 3.015 dx (0.993-1.003 at 4.015 dx), so s0 is kept: a correction for one orientation
    would be wrong by as much for another. In the notched-bar test (crack normal to an axis)
    the dissipated energy per broken bond went from 1.025 G0 to 0.96 G0 with the weight and the
    surface correction, within the 15 % the design asks for.

    Parameters
    ----------
    fracture_energy
        Critical energy release rate G0 (J/m^2), > 0.
    K, mu
        Bulk and shear modulus (Pa).
    delta
        Horizon (m), > 0.

    Returns
    -------
    float
        The critical stretch (dimensionless).

    Raises
    ------
    ValueError
        If an argument is not positive, or the moduli give a non-positive denominator.
    """
    G0 = float(fracture_energy)
    if not (math.isfinite(G0) and G0 > 0.0):
        raise ValueError(f"fracture energy must be a positive number of J/m^2, got {G0!r}")
    if not (math.isfinite(delta) and delta > 0.0):
        raise ValueError(f"the horizon must be a positive length in metres, got {delta!r}")
    if not (K > 0.0 and mu > 0.0):
        raise ValueError(f"K and mu must be positive (got K={K!r}, mu={mu!r})")
    denom = (3.0 * mu + 0.75**4 * (K - 5.0 * mu / 3.0)) * delta
    if denom <= 0.0:
        raise ValueError(
            f"the moduli K={K!r} Pa, mu={mu!r} Pa give a non-positive critical-stretch "
            "denominator 3 mu + (3/4)^4 (K - 5 mu/3)"
        )
    return math.sqrt(G0 / denom)


def implied_fracture_energy(s0: float, K: float, mu: float, delta: float) -> float:
    """The fracture energy (J/m^2) that a critical stretch ``s0`` implies at horizon ``delta`` (m).

    The inverse of :func:`critical_stretch`: ``G0 = s0^2 (3 mu + (3/4)^4 (K - 5 mu / 3)) delta``
    (Madenci & Oterkus 2014). With ``s0`` fixed by a strength, G0 grows in proportion to the
    horizon: a brittle bond law honours a strength or a fracture energy, not both.
    """
    return float(s0) ** 2 * (3.0 * mu + 0.75**4 * (K - 5.0 * mu / 3.0)) * float(delta)


#: Ratio of a lattice beam's flexural strength to its bond tensile strength that is left once
#: the surface offset (1 - dx/h) is taken out: between three-point (1.10-1.14) and four-point
#: (1.03-1.05) bending at h/dx = 10 and 20, centred on the validation runs so that both read
#: within 8 % of the input (docs/ice_strength.md).
FLEXURAL_EXCESS = 1.07

#: Fewest particle layers across the depth for which a flexural strength is converted.
MIN_LAYERS = 4


def tensile_from_flexural(flexural_strength: float, dx: float, depth: float) -> float:
    """The bond tensile strength (Pa) that makes a lattice beam's flexural strength the input.

    ``sigma_t = sigma_f (1 - dx / h) / FLEXURAL_EXCESS``. The outermost particles of a lattice
    body sit dx/2 inside its surface, so in bending the first bond breaks when the fibre at
    h/2 - dx/2 from the neutral axis reaches sigma_t: the beam formula then reads
    sigma_t / (1 - dx/h) at the surface. The remaining factor :data:`FLEXURAL_EXCESS` was
    measured on three- and four-point beams (h/dx = 10 and 20, the validation cases
    ``flexural_strength_*``); docs/ice_strength.md gives the derivation, the measurements and
    the limits (calibrated for h/dx from 10 to 20, horizon 3.015 dx).

    Parameters
    ----------
    flexural_strength
        sigma_f (Pa), from the beam formula at the peak load, > 0.
    dx
        Lattice spacing (m), > 0.
    depth
        Depth h of the body in bending (m): its thickness across which it bends.

    Returns
    -------
    float
        sigma_t (Pa).

    Raises
    ------
    ValueError
        If the depth holds fewer than :data:`MIN_LAYERS` particle layers.
    """
    if not depth >= MIN_LAYERS * dx * (1.0 - 1e-9):
        raise ValueError(f"a flexural strength needs at least {MIN_LAYERS} particle layers across "
                         f"the body's depth (z extent {depth:g} m at dx = {dx:g} m); choose a "
                         "smaller dx or give tensile_strength")
    return float(flexural_strength) * (1.0 - dx / depth) / FLEXURAL_EXCESS


@dataclass(frozen=True)
class IceMaterial:
    """Elastic-brittle ice for the LPS kernels.

    Parameters
    ----------
    density
        Mass density (kg/m^3), > 0.
    youngs_modulus
        Young's modulus E (Pa).
    poisson_ratio
        Poisson's ratio (-1 < nu < 0.5).
    fracture_energy
        Critical energy release rate G0 (J/m^2); gives ``s0`` through :func:`critical_stretch`.
    critical_stretch
        The critical stretch itself (dimensionless, > 0); wins over the others.
    tensile_strength
        The uniaxial tensile strength sigma_t (Pa, > 0) the kernels use: ``s0 = sigma_t / E``,
        at any horizon; wins over ``fracture_energy`` (the ``"ice"`` failure law takes it as its
        tension cut-off; without it, E s0). Under uniaxial stress sigma along x the LPS strain
        is uniform, eps = sigma / E along x and -nu eps across, so a bond of direction n has
        stretch eps (n_x^2 - nu (1 - n_x^2)) (small strain: the stretch of a bond is n.eps.n).
        That is largest, eps, for the bond along the load (n_x = 1); bonds first break when
        eps = s0, i.e. at sigma = E s0. Hence ``s0 = sigma_t / E`` exactly. With none of the
        three given, bonds never break (``s0 = inf``).
    compressive_strength
        Uniaxial compressive strength (Pa), for the ``"ice"`` failure law.
    friction_angle
        Internal friction angle (degrees) of the ``"ice"`` failure law's Coulomb criterion.
    crushed_friction
        Friction coefficient (-) of crushed ice sliding on itself (:mod:`pdfem.pd.failure.crushed_shear`);
        0: none.
    transition_rate
        Ductile-to-brittle transition strain rate (1/s) of the ``"ice"`` law's compressive
        strength; None: no rate dependence.
    rate_exponent
        Exponent of the ductile strength's rise with the strain rate (-).
    """

    density: float
    youngs_modulus: float
    poisson_ratio: float
    fracture_energy: float | None = None
    critical_stretch: float | None = None
    tensile_strength: float | None = None
    compressive_strength: float | None = None
    friction_angle: float = 30.0
    crushed_friction: float = 0.0
    transition_rate: float | None = None
    rate_exponent: float = 1.0 / 3.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.density) and self.density > 0.0):
            raise ValueError(f"density must be a positive number of kg/m^3, got {self.density!r}")
        lps_constants(self.youngs_modulus, self.poisson_ratio)  # validates E and nu
        if self.fracture_energy is not None and not (
            math.isfinite(self.fracture_energy) and self.fracture_energy > 0.0
        ):
            raise ValueError(
                f"fracture energy must be a positive number of J/m^2, got {self.fracture_energy!r}"
            )
        if self.critical_stretch is not None and not (self.critical_stretch > 0.0):
            raise ValueError(f"critical stretch must be positive, got {self.critical_stretch!r}")
        if self.tensile_strength is not None and not (
            math.isfinite(self.tensile_strength) and self.tensile_strength > 0.0
        ):
            raise ValueError(
                f"tensile strength must be a positive number of Pa, got {self.tensile_strength!r}"
            )

    @property
    def K(self) -> float:
        """Bulk modulus (Pa)."""
        return lps_constants(self.youngs_modulus, self.poisson_ratio)[0]

    @property
    def mu(self) -> float:
        """Shear modulus (Pa)."""
        return lps_constants(self.youngs_modulus, self.poisson_ratio)[1]

    @property
    def wave_speed(self) -> float:
        """Bar wave speed sqrt(E / rho) (m/s)."""
        return math.sqrt(self.youngs_modulus / self.density)

    def s0(self, delta: float) -> float:
        """Critical stretch for horizon ``delta`` (m): the given one, else sigma_t / E, else from
        G0, else inf."""
        if self.critical_stretch is not None:
            return float(self.critical_stretch)
        if self.tensile_strength is not None:
            return float(self.tensile_strength) / float(self.youngs_modulus)
        if self.fracture_energy is None:
            return math.inf
        K, mu = lps_constants(self.youngs_modulus, self.poisson_ratio)
        return critical_stretch(self.fracture_energy, K, mu, delta)

    def fracture_energy_at(self, delta: float) -> float:
        """The fracture energy (J/m^2) the bond law has at horizon ``delta`` (m): the given
        G0, or the one ``s0`` implies (:func:`implied_fracture_energy`; inf if bonds never
        break)."""
        s0 = self.s0(delta)
        if self.critical_stretch is None and self.tensile_strength is None \
                and self.fracture_energy is not None:
            return float(self.fracture_energy)
        return implied_fracture_energy(s0, self.K, self.mu, delta)
