"""The ``[[structure]]`` section of a case file: an elastic finite-element structure (its mesh or
mesh model, material, supports, damping and loads), a rigid body with prescribed motion, or a
free-floating ship hull (``kind = "ship"``: its ``ship`` table, :class:`ShipSection`, and the
:class:`ShipConfig` the run builds it from; docs/ship.md).

The steel defaults are declared here with their source.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

from pydantic import Field, ValidationInfo, field_validator, model_validator

from pdfem.case.fields import (Choice, Identifier, Name, Names, Number, Positive, PositiveVec3,
                               Section, Tables, Vec3, Vector, Whole, fail)
from pdfem.case.shapes import MotionPath, directory

#: Structural steel (SI): density and elastic constants of carbon steel as used for ship hulls
#: (e.g. EN 1993-1-1, 3.2.6: E = 210 GPa, nu = 0.3; density 7850 kg/m^3, EN 1991-1-1 Table A.4).
STEEL = {"density": 7850.0, "youngs_modulus": 210e9, "poisson_ratio": 0.3}

#: What a structure is.
Kind = Choice("elastic", "rigid", "ship")
Integrator = Choice("explicit", "implicit")


class SteelSection(Section):
    """Linear elastic material of a structure; the defaults are structural steel."""

    density: Annotated[float, Positive("kg/m^3")] = Field(
        STEEL["density"], description="Mass density (kg/m^3). Default: 7850 (steel, EN 1991-1-1).")
    youngs_modulus: Annotated[float, Positive("Pa")] = Field(
        STEEL["youngs_modulus"], description="Young's modulus (Pa). Default: 210e9 (steel, "
                                             "EN 1993-1-1).")
    poisson_ratio: Annotated[float, Number(gt=-1.0, lt=0.5)] = Field(
        STEEL["poisson_ratio"], description="Poisson's ratio (-), in (-1, 0.5). Default: 0.3 "
                                            "(steel, EN 1993-1-1).")


class DampingSection(Section):
    """Rayleigh damping C = alpha M + beta K."""

    alpha: Annotated[float, Number("1/s", ge=0.0)] = Field(
        0.0, description="Mass-proportional coefficient (1/s). Default: 0.")
    beta: Annotated[float, Number("s", ge=0.0)] = Field(
        0.0, description="Stiffness-proportional coefficient (s). Default: 0.")


class PulseSection(Section):
    """Trapezoidal time history: 0 before start, rises linearly to 1, holds, falls to 0."""

    start: Annotated[float, Number("s", ge=0.0)] = Field(
        0.0, description="Time the load starts (s). Default: 0.")
    rise: Annotated[float, Number("s", ge=0.0)] = Field(
        0.0, description="Rise time from 0 to full load (s). Default: 0.")
    hold: Annotated[float, Number("s", ge=0.0)] | None = Field(
        None, description="Time at full load (s). Default: forever (the load stays on).")
    fall: Annotated[float, Number("s", ge=0.0)] = Field(
        0.0, description="Fall time from full load to 0 (s), after hold; with hold only. "
                         "Default: 0.")
    needs = (("fall", "hold", "the load falls after its hold; without hold it stays on, so "
                              "give hold (s) or remove fall"),)


class LoadSection(Section):
    """A uniform surface load on a mesh group."""

    group: Name = Field(description="Mesh group (surface) the load acts on. Required.")
    pressure: Annotated[float, Number("Pa")] = Field(
        0.0, description="Pressure, positive into the structure (Pa). Default: 0.")
    traction: Annotated[Vec3, Vector("Pa")] = Field(
        (0.0, 0.0, 0.0), description="Traction vector (Pa). Default: [0, 0, 0].")
    pulse: PulseSection = Field(default_factory=PulseSection,
                                description="Time history `{start, rise, hold, fall}` (s). "
                                            "Default: on from t = 0.")


class SupportSection(Section):
    """A support holding only some displacement components of a mesh group (roller, symmetry
    plane)."""

    group: Name = Field(description="Mesh group whose nodes are supported. Required.")
    components: Names = Field(
        description='Components held at zero, a list of "x", "y", "z" (e.g. ["z"] for a roller, '
                    '["x"] for a symmetry plane x = const). Required.')

    @field_validator("components")
    @classmethod
    def _xyz(cls, components: tuple[str, ...]) -> tuple[str, ...]:
        bad = [c for c in components if c not in ("x", "y", "z")]
        if bad or not components:
            raise fail('expected a non-empty list of "x", "y", "z"', list(components))
        return components


class MotionSection(Section):
    """Prescribed rigid-body motion (rigid bodies), or the moving frame that carries an elastic
    structure (rotation about a fixed shaft axis plus translation, docs/rotating_structures.md)."""

    velocity: Annotated[Vec3, Vector("m/s")] = Field((0.0, 0.0, 0.0), description="Velocity (m/s). "
                                                                 "Default: [0, 0, 0].")
    angular_velocity: Annotated[Vec3, Vector("rad/s")] = Field(
        (0.0, 0.0, 0.0), description="Angular velocity (rad/s). Default: [0, 0, 0].")
    center: Annotated[Vec3, Vector("m")] = Field(
        (0.0, 0.0, 0.0), description="Centre of rotation at t = 0 (m). Default: [0, 0, 0].")
    path: MotionPath | None = Field(
        None, description="Translation path `[[t, ux, uy, uz], ...]` (s, m) instead of velocity: "
                          "piecewise linear, t strictly increasing, first t >= 0; the first "
                          "point's displacement before it (the body starts there), the last "
                          "point's after it; the rotation stays angular_velocity about the "
                          "moving centre (an elastic structure's frame follows it too, e.g. a "
                          "panel on a towed hull). Default: none (constant velocity).")
    ramp_time: Annotated[float, Number("s", ge=0.0)] = Field(
        0.0, description="Elastic structures only: time over which velocity and "
                         "angular_velocity rise linearly from rest, from t = 0 (s). "
                         "Default: 0 (full speed at once: a turning structure starts in its "
                         "steady state, the static equilibrium of the rotating frame; "
                         "docs/rotating_structures.md).")

    @model_validator(mode="after")
    def _velocity_or_path(self) -> "MotionSection":
        if self.path is not None and "velocity" in self.model_fields_set:
            raise fail("give either velocity (m/s) or path ([[t, ux, uy, uz], ...] in s, m), "
                       "not both", key="path")
        return self


class ShipSection(Section):
    """A free-floating rigid hull (``kind = "ship"``): mass, inertia, start and propulsion."""

    mass: Annotated[float, Positive("kg")] | None = Field(
        None, description="Mass (kg) of the whole ship, the structures attached to it "
                          "(attached_to) included. Default: the displaced mass of the hull as "
                          "meshed (water density x submerged volume), i.e. floating at its mesh "
                          "draught.")
    center_of_gravity: Annotated[Vec3, Vector("m")] | None = Field(
        None, description="Centre of gravity of the whole ship (attached structures "
                          "included) in the mesh's coordinates (m). Default: above the hull's "
                          "centre of buoyancy, at the water surface.")
    radii_of_gyration: Annotated[PositiveVec3, Vector("m", positive=True)] | None = Field(
        None, description="Radii of gyration of the whole ship (attached structures "
                          "included) about the body x (roll), y (pitch), z (yaw) axes "
                          "through the centre of gravity (m), each > 0. Default: 0.4 x breadth, "
                          "0.25 x length, 0.25 x length of the hull's waterline (typical ship "
                          "values).")
    initial_displacement: Annotated[Vec3, Vector("m")] = Field(
        (0.0, 0.0, 0.0), description="Rigid displacement of the hull at t = 0 from the mesh "
                                     "(m), e.g. to release it off equilibrium. Default: 0.")
    initial_rotation: Annotated[Vec3, Vector("rad")] = Field(
        (0.0, 0.0, 0.0), description="Rotation vector (axis x angle, rad) about the centre of "
                                     "gravity applied at t = 0. Default: 0.")
    initial_velocity: Annotated[Vec3, Vector("m/s")] = Field(
        (0.0, 0.0, 0.0), description="Velocity of the centre of gravity at t = 0 (m/s). "
                                     "Default: 0.")
    initial_angular_velocity: Annotated[Vec3, Vector("rad/s")] = Field(
        (0.0, 0.0, 0.0), description="Angular velocity at t = 0 (rad/s, world axes). "
                                     "Default: 0.")
    thrust: Annotated[float, Number("N")] = Field(
        0.0, description="Constant thrust along the hull's x axis (N). Default: 0.")
    surge_speed: Annotated[float, Number("m/s")] | None = Field(
        None, description="Hold the x velocity of the centre of gravity at this speed (m/s), "
                          "reached linearly over ramp_time. Default: free surge.")
    ramp_time: Annotated[float, Number("s", ge=0.0)] = Field(
        0.0, description="Time to reach surge_speed from 0 (s); with surge_speed only. "
                         "Default: 0 (at once).")
    needs = (("ramp_time", "surge_speed", "ramp_time is the time to reach surge_speed; give "
              "surge_speed (m/s) or remove ramp_time (a free ship's surge has no ramp)"),)


@dataclass(frozen=True)
class ShipConfig:
    """A ship's inputs with the water and gravity of its case (SI)."""

    section: ShipSection
    water_density: float | None      # kg/m^3; None: the case has no [water]
    water_level: float               # m
    gravity: tuple[float, float, float]  # m/s^2


def ship_config(s: "StructureSection", water, gravity) -> ShipConfig | None:
    """The :class:`ShipConfig` of a ``kind = "ship"`` structure (``None`` for other kinds);
    ``water``: the case's water section or ``None``."""
    if s.kind != "ship":
        return None
    return ShipConfig(s.ship or ShipSection(), None if water is None else water.density,
                      0.0 if water is None else water.level, tuple(gravity))


#: The ``[[structure]]`` keys that only some kinds take (every kind takes the others: name,
#: kind, mesh, params, contact_group); a key given to another kind is refused, not ignored.
KIND_KEYS = {"material": ("elastic",), "element_order": ("elastic",), "integrator": ("elastic",),
             "damping": ("elastic",), "fixed_groups": ("elastic",), "supports": ("elastic",),
             "loads": ("elastic",), "attached_to": ("elastic",),
             "motion": ("elastic", "rigid"), "ship": ("ship",)}

#: What a structure of each kind is, for the message refusing a key it does not take.
KIND_WHY = {
    "elastic": "only a ship has a ship table; an elastic structure's mass and stiffness come "
               "from its mesh and material",
    "rigid": "a rigid structure moves as prescribed by its motion (velocity or path, "
             "angular_velocity, center) and has no material, elements, damping, supports or "
             "loads",
    "ship": "a ship is a rigid hull floating free under gravity, water and ice, with its mass "
            "and inertia in its ship table, driven by ship.thrust or ship.surge_speed, and has "
            "no material, elements, damping, supports, loads or prescribed motion",
}


def _is_gmsh(path: Path) -> bool:
    """Whether ``path`` starts like a gmsh .msh file (ASCII or binary: ``$MeshFormat``)."""
    try:
        with open(path, "rb") as fh:
            return fh.read(64).lstrip().startswith(b"$MeshFormat")
    except OSError:
        return False


class StructureSection(Section):
    """One structure: an elastic FE model or a rigid body with prescribed motion."""

    name: Identifier = Field(description="Structure name (letters, digits, _ - and ., not "
                                         "first), unique among bodies and structures. Required.")
    kind: Kind = Field(
        "elastic", description='"elastic" (finite elements), "rigid" (prescribed motion) or '
                               '"ship" (free-floating rigid hull, 6 DOF, needs [water]). '
                               'Default: "elastic".')
    mesh: Name = Field(
        description="A model of models/ by name (hull_panel, propeller_blade, indenters), a .py "
                    "model file or a .msh file (relative to the case file). Required.")
    params: dict[str, Any] = Field(
        default_factory=dict,
        description="Model parameters (SI), e.g. `{ element_size = 0.08 }` (m); each model "
                    "script's docstring lists them. Models only. Default: the model's defaults.")
    material: SteelSection = Field(
        default_factory=SteelSection,
        description="`density` (kg/m^3), `youngs_modulus` (Pa), `poisson_ratio`. "
                    "Default: steel (7850, 210e9, 0.3).")
    fixed_groups: Names = Field((), description="Mesh groups clamped in place (all three "
                                                "components). Default: [].")
    supports: Tables(SupportSection) = Field(
        (), description='List of `{group, components = ["x", "z"]}`: only the named displacement '
                        "components of the group held at zero (rollers, symmetry planes); a "
                        "reaction per support and component is written. Default: none.")
    element_order: Annotated[int, Whole(1)] = Field(
        2, description="Elastic structures: 2 = quadratic elements (10-node tetrahedra, 20-node "
                       "hexahedra) raised from the mesh; 1 = linear elements, which lock in "
                       "bending (a 12 mm plate 1.5 to 3.6 times too stiff, see "
                       "docs/structures_convergence.md). Default: 2.")
    integrator: Integrator = Field(
        "explicit", description='Elastic structures: "explicit" (central differences: the step '
                                "is limited by the smallest element; the structure subcycles "
                                'inside the ice\'s step) or "implicit" (average-acceleration '
                                "Newmark, unconditionally stable: one factorisation, then one "
                                "solve per step; period error (omega dt)^2 / 12; "
                                "docs/structures_time_integration.md). Implicit: elastic "
                                "structures at rest or in a prescribed moving frame (motion), "
                                "not attached to a ship; ice contact amends each step by its "
                                "impulses; a case without ice needs run.time_step. "
                                'Default: "explicit".')
    contact_group: Name = Field("contact", description='Mesh group facing the ice. '
                                                      'Default: "contact".')
    damping: DampingSection = Field(default_factory=DampingSection,
                                    description="Rayleigh `alpha` (1/s), `beta` (s). Default: 0, 0.")
    loads: Tables(LoadSection) = Field(
        (), description="List of `{group, pressure (Pa) or traction (Pa, vector), pulse = {start, "
                        "rise, hold, fall} (s)}`. Default: none.")
    motion: MotionSection = Field(
        default_factory=MotionSection,
        description="Rigid bodies: `velocity` (m/s) or a translation `path` "
                    "`[[t, ux, uy, uz], ...]` (s, m), `angular_velocity` (rad/s), `center` (m). "
                    "Elastic structures: the moving frame they are solved in, `velocity`, "
                    "`angular_velocity` (fixed axis through `center`), `center`, `ramp_time` (s) "
                    "(docs/rotating_structures.md). Default: at rest.")

    attached_to: Name | None = Field(
        None, description="Elastic structures only: the name of a ship (kind = \"ship\", listed "
                          "before this structure) whose hull carries it, e.g. an elastic bow "
                          "panel: its frame moves with the ship (position, attitude, velocity, "
                          "acceleration) and the loads on it reach the ship through its supports; "
                          "the ship's mass, centre of gravity and radii of gyration include it, "
                          "and it may carry up to all of the ship's mass (docs/ship.md). The "
                          "mesh is in the hull mesh's coordinates. Default: none.")

    ship: ShipSection | None = Field(
        None, description="Ships only (kind = \"ship\"): `mass` (kg), `center_of_gravity` (m), "
                          "`radii_of_gyration` (m), `initial_displacement` (m), "
                          "`initial_rotation` (rad), `initial_velocity` (m/s), "
                          "`initial_angular_velocity` (rad/s), `thrust` (N), `surge_speed` "
                          "(m/s), `ramp_time` (s). Default: floating at the mesh draught, at "
                          "rest (docs/ship.md).")

    @field_validator("mesh")
    @classmethod
    def _mesh_file(cls, mesh: str, info: ValidationInfo) -> str:
        if not mesh.endswith((".msh", ".py")):
            return mesh
        path = Path(mesh) if Path(mesh).is_absolute() else directory(info) / mesh
        if not path.is_file():
            raise fail(f"no such file ({path}); give a .msh file, a .py model file, or the name "
                       "of a model in models/", mesh)
        if mesh.endswith(".msh") and not _is_gmsh(path):
            raise fail(f"{path} is not a gmsh mesh file (it does not start with $MeshFormat); "
                       "write it from gmsh as .msh (format 4.1 or 2.2)", mesh)
        return str(path)

    @field_validator("params", mode="before")
    @classmethod
    def _params_table(cls, params: Any) -> Any:
        if not isinstance(params, dict):
            raise fail("expected a table of model parameters", params)
        return params

    @model_validator(mode="after")
    def _consistent(self) -> "StructureSection":
        if self.params and self.mesh.endswith(".msh"):
            raise fail("model parameters apply to a model (name or .py), not to a .msh file",
                       key="params")
        if self.element_order > 2:
            raise fail("element_order must be 1 (linear) or 2 (quadratic)", self.element_order,
                       key="element_order")
        for key in KIND_KEYS:
            if key in self.model_fields_set and self.kind not in KIND_KEYS[key]:
                raise fail(f'{key} has no effect on a structure of kind = "{self.kind}": '
                           f"{KIND_WHY[self.kind]}; remove it ({key} is a key of "
                           + " and ".join(KIND_KEYS[key]) + " structures)", key=key)
        if self.kind == "rigid" and "ramp_time" in self.motion.model_fields_set:
            raise fail("ramp_time is for elastic structures only; a rigid body moves at its "
                       "velocity from t = 0 (or follows its path)", self.motion.ramp_time,
                       key="motion.ramp_time")
        if self.attached_to is not None and "motion" in self.model_fields_set:
            raise fail("only an elastic structure without a motion rides on a ship (its frame is "
                       "the ship's)", self.attached_to, key="attached_to")
        if self.integrator == "implicit" and self.attached_to is not None:
            raise fail("the implicit integrator is for elastic structures standing still or in "
                       "a prescribed moving frame (motion), not for a structure attached to a "
                       "ship (its frame follows the ship's dynamics step by step); use "
                       'integrator = "explicit" for this one', self.integrator, key="integrator")
        return self
