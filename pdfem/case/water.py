"""The ``[water]`` section of a case file: still water with an optional current (SI units).

With a ``[water]`` section every ice body floats: each particle gets the buoyancy of the
submerged fraction of its cell and a drag against its velocity relative to the current
(:class:`pdfem.forces.water.Water`, docs/water.md). Gravity is then (0, 0, -9.81) m/s^2 unless
``run.gravity`` is given; the water surface is the plane z = ``level`` and gravity must point
down z (-z).
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from pdfem.case.fields import Number, Positive, Section, Vec3, Vector

#: Standard gravity (m/s^2, down z), the default of a case with water and no ``run.gravity``.
STANDARD_GRAVITY = (0.0, 0.0, -9.81)


class WaterSection(Section):
    """Still water below z = level, with a uniform current (SI units)."""

    density: Annotated[float, Positive("kg/m^3")] = Field(
        1025.0, description="Water density (kg/m^3). Default: 1025 (sea water).")
    level: Annotated[float, Number("m")] = Field(
        0.0, description="z of the still water surface (m). Place a floating ice sheet at its "
                         "draught: bottom at level - (rho_ice/rho_water) h. Default: 0.")
    current: Annotated[Vec3, Vector("m/s")] = Field(
        (0.0, 0.0, 0.0), description="Velocity of the water (m/s); drag acts against the ice's "
                                     "velocity relative to it. Default: [0, 0, 0].")
    linear_drag: Annotated[float, Number("1/s", ge=0.0)] = Field(
        0.0, description="Linear drag as a damping rate of submerged ice (1/s): force density "
                         "-rho_ice * linear_drag * phi * (v - current), phi the submerged "
                         "fraction of the particle's cell. Default: 0.")
    drag_coefficient: Annotated[float, Number(ge=0.0)] = Field(
        0.0, description="Quadratic drag coefficient Cd (-) of each submerged particle's cell "
                         "(a cube of side dx): force density -0.5 rho_water Cd phi |u| u / dx "
                         "with u = v - current (fragment-scale drag; it grows with 1/dx, see "
                         "docs/water.md). Default: 0.")
    added_mass: Annotated[float, Number(ge=0.0)] = Field(
        0.0, description="Added-mass coefficient Ca (-): a submerged particle's inertia becomes "
                         "rho_ice + Ca rho_water phi per unit volume (the water it carries "
                         "along); 0 = off. Default: 0 (off).")


def gravity_with_water(gravity: Vec3, given: bool, water: WaterSection | None) -> Vec3:
    """Gravity of a case (m/s^2): ``gravity`` if ``given`` or without water, else
    :data:`STANDARD_GRAVITY`.

    Parameters
    ----------
    gravity
        ``run.gravity`` as read (m/s^2).
    given
        Whether the case file gave ``run.gravity``.
    water
        The ``[water]`` section, None without one.
    """
    return gravity if given or water is None else STANDARD_GRAVITY
