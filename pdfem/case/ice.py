"""The ``[[ice]]`` section of a case file: a peridynamic ice body, its material, regions and
pre-cracks.

The sea-ice material defaults are declared here, with their sources; :mod:`pdfem.run.build_ice`
turns the material section into the kernels' :class:`pdfem.pd.materials.lps.IceMaterial`.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import Field, model_validator

from pdfem.case.fields import (Identifier, Name, Number, Positive, Section, Tables, Vec3,
                               Vector, fail)
from pdfem.case.shapes import (BoxShape, MotionPath, NamedRegionSection, RegionName,
                               RegionSection, ShapeSection)

MAX_HORIZON_FACTOR = 20.0
"""Largest horizon / dx: a particle then has 33,400 neighbours (the lattice points within 20
spacings), against 122 at the usual 3.015, and its bonds take about 0.5 MB (30 B each, half of
them its own); the size estimates' lattice tables (``pdfem.run.estimates``) grow as the cube of
horizon / dx."""

#: Sea-ice defaults (SI), with their sources in the descriptions of :class:`IceMaterialSection`.
SEA_ICE = {"density": 900.0, "youngs_modulus": 4.1e9, "poisson_ratio": 0.3, "fracture_energy": 10.0}


class IceMaterialSection(Section):
    """Elastic-brittle ice; the defaults are first-year sea ice.

    The bonds break at a threshold given in one of three ways: a strength (``tensile_strength``
    or ``flexural_strength``, Pa: what engineers measure; the threshold then does not depend on
    the particle spacing), the fracture energy (``fracture_energy``, the default: the threshold
    scales as horizon^-1/2) or the critical stretch itself. With a strength, the fracture energy
    the bond law implies follows from strength and horizon (``docs/ice_strength.md``), so an
    explicit ``fracture_energy`` beside a strength is an error.
    """

    density: Annotated[float, Positive("kg/m^3")] = Field(
        SEA_ICE["density"], description="Mass density (kg/m^3). Default: 900 (first-year sea ice, "
        "observed 840-940 depending on brine and air content; Timco & Frederking 1996).")
    youngs_modulus: Annotated[float, Positive("Pa")] = Field(
        SEA_ICE["youngs_modulus"], description="Young's modulus (Pa). Default: 4.1e9 (mean of "
        "Kujala's beam tests on Baltic sea ice, range 3.2-5.4 GPa).")
    poisson_ratio: Annotated[float, Number(gt=-1.0, lt=0.5)] = Field(
        SEA_ICE["poisson_ratio"], description="Poisson's ratio (-), in (-1, 0.5). Default: 0.3 "
        "(the usual value for sea ice, e.g. Timco & Weeks 2010).")
    # -- what breaks the bonds: one strength, or fracture_energy, or critical_stretch ---------
    tensile_strength: Annotated[float, Positive("Pa")] | None = Field(
        None, description="Uniaxial tensile strength (Pa); bonds break at stretch "
        "tensile_strength / youngs_modulus at any dx. Not with flexural_strength, fracture_energy "
        "or critical_stretch. Default: not given (sea ice 0.2-0.8 MPa, Timco & Weeks 2010).")
    flexural_strength: Annotated[float, Positive("Pa")] | None = Field(
        None, description="Flexural strength (Pa) from the beam formula at the peak load; the "
        "bond threshold is derived from it (docs/ice_strength.md). Not with tensile_strength, "
        "fracture_energy or critical_stretch. Default: not given (sea ice 0.4-0.9 MPa, "
        "Timco & O'Brien 1994).")
    fracture_energy: Annotated[float, Positive("J/m^2")] = Field(
        SEA_ICE["fracture_energy"], description="Critical energy release rate G0 (J/m^2); gives "
        "the critical bond stretch. Not with critical_stretch or a strength. Default: 10 (an order "
        "of magnitude; reported values scatter with specimen size and loading rate, Timco & Weeks "
        "2010); not used when a strength is given.")
    critical_stretch: Annotated[float, Positive()] | None = Field(
        None, description="Critical bond stretch s0 (-), instead of fracture_energy. "
        "Default: from fracture_energy.")
    failure: Literal["critical_stretch", "ice"] = Field(
        "critical_stretch", description="Failure law of the bonds: \"critical_stretch\" (bonds "
        "break in tension only) or \"ice\" (tension, and compressive-shear crushing at "
        "compressive_strength, rising with confinement; docs/ice_failure.md). "
        "Default: \"critical_stretch\".")
    compressive_strength: Annotated[float, Positive("Pa")] | None = Field(
        None, description="Uniaxial compressive strength (Pa) of the \"ice\" failure law; "
        "required with it. Sea ice: about 1-5 MPa at ice-structure strain rates (Timco & Weeks "
        "2010). Default: none.")
    friction_angle: Annotated[float, Number("deg", ge=0.0, lt=60.0)] = Field(
        30.0, description="Internal friction angle (degrees) of the \"ice\" law's Coulomb "
        "criterion: the compressive strength rises by (1 + sin phi) / (1 - sin phi) times the "
        "confining pressure. Default: 30 (Schulson & Duval 2009: friction coefficient 0.5-0.9).")
    crushed_friction: Annotated[float, Number("-", ge=0.0, le=2.0)] = Field(
        default_factory=lambda data: math.tan(math.radians(data["friction_angle"])),
        description="Friction coefficient (-) of the \"ice\" law's crushed ice sliding on "
        "itself: a shear spring with Coulomb slip on every pushing crushed bond holds a crushed "
        "layer in the contact, so that edge crushing stays at Korzhavin's pressures "
        "(docs/ice_failure.md); 0 turns it off (the crushed layer then flows out frictionless: "
        "edge crushing at 0.23-0.37 compressive_strength). Default: tan(friction_angle), 0.577 at 30 degrees: "
        "in biaxial tests on columnar S2 ice the internal friction coefficient that governs "
        "Coulombic faulting is closely similar to the coefficient of static friction across "
        "the fault (Acta Materialia 2006, terminal and post-terminal failure of S2 freshwater "
        "ice).")

    transition_rate: Annotated[float, Positive("1/s")] | None = Field(
        None, description="Ductile-to-brittle transition strain rate (1/s) of the \"ice\" law: "
        "below it the compressive strength falls as (rate / transition_rate)^rate_exponent "
        "(ductile ice), at and above it it is compressive_strength. Ice: 1e-4 to 1e-3 "
        "(Schulson & Duval 2009). Default: none (no rate dependence).")
    rate_exponent: Annotated[float, Number(gt=0.0, le=1.0)] = Field(
        1.0 / 3.0, description="Exponent of the ductile strength's rise with the strain rate (-), "
        "with transition_rate. Default: 1/3 (Glen's flow law, n = 3).")

    needs = (("rate_exponent", "transition_rate", 'rate_exponent shapes the "ice" law\'s '
              "ductile strength below transition_rate; give transition_rate (1/s) or remove "
              "rate_exponent"),)

    @model_validator(mode="after")
    def _one_criterion(self) -> "IceMaterialSection":
        given = self.model_fields_set
        if {"tensile_strength", "flexural_strength"} <= given:
            raise fail("give either tensile_strength or flexural_strength (Pa), not both; the "
                       "other follows from it (docs/ice_strength.md)", key="flexural_strength")
        strength = next((k for k in ("tensile_strength", "flexural_strength") if k in given), None)
        if strength and "critical_stretch" in given:
            raise fail(f"give either {strength} (Pa) or critical_stretch, not both: the strength "
                       "sets the critical stretch", key="critical_stretch")
        if strength and "fracture_energy" in given:
            raise fail(f"give either {strength} (Pa) or fracture_energy (J/m^2), not both: a "
                       "brittle bond law cannot honour both, and with a strength the fracture "
                       "energy follows from strength and horizon (docs/ice_strength.md)",
                       key="fracture_energy")
        if {"fracture_energy", "critical_stretch"} <= given:
            raise fail("give either fracture_energy (J/m^2) or critical_stretch, not both",
                       key="critical_stretch")
        if self.failure == "ice" and self.compressive_strength is None:
            raise fail('failure = "ice" needs compressive_strength (Pa), e.g. 3.0e6',
                       key="compressive_strength")
        if self.failure != "ice":
            for key in ("compressive_strength", "friction_angle", "crushed_friction",
                        "transition_rate", "rate_exponent"):
                if key in self.model_fields_set:
                    raise fail(f'{key} is a parameter of failure = "ice"; set failure = "ice" '
                               "or remove it", key=key)
        return self


class VelocitySection(Section):
    """Particles in a region move as prescribed: a velocity (ramped from 0 over ramp_time) or a
    displacement path."""

    name: RegionName | None = Field(
        None, description="Name of the region's reaction history `loads/<body>.<name>` (letters, "
                          "digits, _ + -), unique in the body. Default: prescribed1, "
                          "prescribed2, ... by position in the list.")
    region: RegionSection = Field(description="The region: `box`, `cylinder` or `sphere` (m). "
                                              "Required.")
    velocity: Annotated[Vec3, Vector("m/s")] | None = Field(
        None,
        description="Prescribed velocity (m/s). Default: none (required unless path is given).")
    ramp_time: Annotated[float, Number("s", ge=0.0)] = Field(
        0.0, description="Time over which the velocity ramps up linearly from 0 (s). With "
                         "velocity only. Default: 0.")
    path: MotionPath | None = Field(
        None, description="Displacement path `[[t, ux, uy, uz], ...]` (s, m) instead of velocity: "
                          "piecewise linear, t strictly increasing, first t >= 0; the first "
                          "point's displacement before it (the region starts there), the last "
                          "point's after it. Default: none (give velocity or path).")

    @model_validator(mode="after")
    def _one_motion(self) -> "VelocitySection":
        if (self.velocity is None) == (self.path is None):
            both = self.path is not None
            raise fail("give either velocity (m/s) or path ([[t, ux, uy, uz], ...] in s, m)"
                       + (", not both" if both else ""), key="path" if both else "velocity")
        if self.path is not None and "ramp_time" in self.model_fields_set:
            raise fail("ramp_time goes with velocity; a path prescribes the displacement at "
                       "every time itself", key="ramp_time")
        return self


class CrackSection(Section):
    """A planar pre-crack: the part of the plane (point, normal) inside box; every bond crossing
    it is broken at t = 0."""

    point: Annotated[Vec3, Vector("m")] = Field(
        description="A point of the crack plane (m). Required.")
    normal: Annotated[Vec3, Vector()] = Field(
        description="Normal of the crack plane (any length, not zero). Required.")
    box: BoxShape = Field(description="`{min, max}` (m): the part of the plane that is cracked. "
                                      "Required.")

    @model_validator(mode="after")
    def _normal_not_zero(self) -> "CrackSection":
        if math.hypot(*self.normal) == 0.0:
            raise fail("the crack plane's normal must not be zero", list(self.normal), key="normal")
        try:
            self.box.build()
        except ValueError as exc:
            raise fail(str(exc), key="box") from None
        return self


class IceSection(Section):
    """One peridynamic ice body."""

    name: Identifier = Field(description="Body name (letters, digits, _ - and ., not first), "
                                         "unique among bodies and structures. Required.")
    dx: Annotated[float, Positive("m")] = Field(description="Lattice spacing (m). Required.")
    horizon_factor: Annotated[float, Number(gt=1.0)] = Field(
        3.015, description="Horizon as a multiple of dx (-), at most 20. Not with horizon. "
                           "Default: 3.015.")
    horizon: Annotated[float, Positive("m")] | None = Field(
        None, description="Horizon (m), instead of horizon_factor; at most 20 dx. Default: "
                           "horizon_factor * dx.")
    shape: ShapeSection = Field(
        description="`box = {min, max}`, `cylinder = {base, axis, radius, length}`, "
                    "`sphere = {center, radius}` or `mesh = {file, group}` (a closed surface mesh, "
                    "relative to the case file) (m). Required.")
    material: IceMaterialSection = Field(
        default_factory=IceMaterialSection,
        description="`density` (kg/m^3), `youngs_modulus` (Pa), `poisson_ratio`, and one of "
                    "`tensile_strength` (Pa), `flexural_strength` (Pa), `fracture_energy` (J/m^2) "
                    "or `critical_stretch`. Default: sea ice (900, 4.1e9, 0.3, 10).")
    initial_velocity: Annotated[Vec3, Vector("m/s")] = Field(
        (0.0, 0.0, 0.0), description="Initial velocity of every particle (m/s). Default: [0, 0, 0].")
    fixed: Tables(NamedRegionSection) = Field(
        (), description="Regions held in place (m): `{box = {...}}` or `{name, box = {...}}` "
                        "(or cylinder, sphere); each region's reaction (N) is written as "
                        "`loads/<body>.<name>` (names default to fixed1, fixed2, ...). "
                        "Default: none.")
    prescribed_velocity: Tables(VelocitySection) = Field(
        (), description="List of `{name, region, velocity (m/s), ramp_time (s)}` or `{name, "
                        "region, path = [[t, ux, uy, uz], ...] (s, m)}`; each region's reaction "
                        "(N) is written as `loads/<body>.<name>` (names default to prescribed1, "
                        "...). Default: none.")
    no_fail: Tables(RegionSection) = Field(
        (), description="Regions whose bonds never break (m). Default: none.")
    cracks: Tables(CrackSection) = Field(
        (), description="Planar pre-cracks `{point, normal, box}` (m). Default: none.")

    def region_names(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """Names of the fixed and the prescribed regions (given, or fixed<k>, prescribed<k> by
        position in their list, from 1)."""
        fixed = tuple(r.name or f"fixed{k + 1}" for k, r in enumerate(self.fixed))
        driven = tuple(r.name or f"prescribed{k + 1}"
                       for k, r in enumerate(self.prescribed_velocity))
        return fixed, driven

    @model_validator(mode="after")
    def _unique_region_names(self) -> "IceSection":
        seen: set[str] = set()
        for key, names in zip(("fixed", "prescribed_velocity"), self.region_names()):
            for k, name in enumerate(names):
                if name in seen:
                    raise fail(f"the region name '{name}' is used twice in this body; names of "
                               "fixed and prescribed regions must be unique within a body "
                               "(defaults: fixed<k>, prescribed<k>)", name, key=f"{key}[{k}].name")
                seen.add(name)
        return self

    def horizon_length(self) -> float:
        """The horizon in m (given, or horizon_factor * dx)."""
        return self.horizon if self.horizon is not None else self.horizon_factor * self.dx

    @model_validator(mode="after")
    def _horizon_and_spacing(self) -> "IceSection":
        if self.horizon is not None and "horizon_factor" in self.model_fields_set:
            raise fail("give either horizon (m) or horizon_factor (multiple of dx), not both",
                       key="horizon")
        horizon = self.horizon_length()
        if horizon <= self.dx:
            raise fail(f"the horizon must be larger than the spacing dx = {self.dx:g} m "
                       "(3 dx is usual: horizon_factor = 3.015)", horizon, key="horizon")
        if horizon > MAX_HORIZON_FACTOR * self.dx:
            key = "horizon" if self.horizon is not None else "horizon_factor"
            raise fail(f"the horizon is {horizon / self.dx:.3g} dx; choose at most "
                       f"{MAX_HORIZON_FACTOR:g} dx (then a particle has 33,400 neighbours: the "
                       "family grows as (4/3) pi (horizon / dx)^3; 3.015 dx is usual)",
                       self.horizon if key == "horizon" else self.horizon_factor, key=key)
        lo, hi = self.shape.geometry.bounds()
        thinnest = min(hi[k] - lo[k] for k in range(3))
        if thinnest < self.dx * (1 - 1e-9):
            raise fail(f"the spacing is larger than the body's thinnest extent ({thinnest:g} m); "
                       "choose a smaller dx", self.dx, key="dx")
        return self
