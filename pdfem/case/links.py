"""The ``[[contact]]`` and ``[[monitor]]`` sections: what meets what, and where to probe.

Both name bodies and structures of the same case; that the names exist is checked by
:class:`pdfem.case.casefile.CaseFile`.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from pdfem.case.fields import Identifier, Name, Number, Section, Vec3, Vector


class ContactSection(Section):
    """Contact between one ice body and one structure's contact surface."""

    ice: Name = Field(description="Name of the ice body. Required (without any [[contact]]: "
                                  "every ice body meets every structure).")
    structure: Name = Field(description="Name of the structure whose contact surface it meets. "
                                        "Required.")
    name: Identifier | None = Field(
        None, description='Name of the pair (its load history). Default: `"<ice>-<structure>"`.')
    friction: Annotated[float, Number(ge=0.0)] = Field(
        0.0, description="Coulomb friction coefficient (-). Default: 0.")
    search_radius: Annotated[float, Number("m", ge=0.0)] = Field(
        0.0, description="How far behind the surface a particle is caught (m); 0 = dx / 2 of the "
                         "ice. Default: 0 (dx / 2).")


class MonitorSection(Section):
    """A probe on an elastic structure, recorded at every coupling step."""

    name: Identifier = Field(description="Probe name (letters, digits, _ - and ., not first), "
                                         "unique among monitors. Required.")
    structure: Name = Field(description="Name of the (elastic) structure. Required.")
    point: Annotated[Vec3, Vector("m")] = Field(
        description="Probe point (m): displacement of the nearest node and von Mises stress of "
                    "the element whose centre is nearest. Required.")
