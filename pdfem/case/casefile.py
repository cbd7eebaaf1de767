"""The whole case file: its sections and the checks across them (names that must exist or be
unique). :meth:`CaseFile.model_json_schema` is the JSON Schema that ``pdfem schema`` prints."""

from __future__ import annotations

from pydantic import ConfigDict, Field, model_validator

from pdfem.case.fields import Section, Tables, fail
from pdfem.case.ice import IceSection
from pdfem.case.links import ContactSection, MonitorSection
from pdfem.case.run import RunSection
from pdfem.case.structure import StructureSection
from pdfem.case.water import WaterSection


#: The ``[water]`` keys that act on ice bodies only (a ship feels density and level).
ICE_ONLY_WATER_KEYS = ("current", "linear_drag", "drag_coefficient", "added_mass")


def _names(kind: str, names: list[str]) -> str:
    return f"no {kind} of that name; the case has: " + (", ".join(names) or "(none)")


class CaseFile(Section):
    """A pdfem case: one run of peridynamic ice bodies and finite-element structures (SI units)."""

    model_config = ConfigDict(title="pdfem case file")

    run: RunSection = Field(description="Time loop, output, checkpoints. Required.")
    ice: Tables(IceSection) = Field((), description="Peridynamic ice bodies. Default: none.")
    structure: Tables(StructureSection) = Field((), description="Structures (elastic or rigid). "
                                                                "Default: none.")
    contact: Tables(ContactSection) = Field(
        (), description="Which ice body meets which structure. Default: every pair.")
    monitor: Tables(MonitorSection) = Field((), description="Probes on structures. Default: none.")
    water: WaterSection | None = Field(
        None, description="Water the ice floats in (buoyancy, drag, added mass; docs/water.md) "
                          "and ships float in (density and level: their hydrostatics); refused "
                          "in a case with neither. Default: none.")

    @model_validator(mode="after")
    def _cross_references(self) -> "CaseFile":
        if not self.ice and not self.structure:
            raise fail("a case needs at least one [[ice]] body or [[structure]]", key="ice")
        names = [b.name for b in self.ice] + [s.name for s in self.structure]
        paths = [f"ice[{i}]" for i in range(len(self.ice))] + \
                [f"structure[{i}]" for i in range(len(self.structure))]
        for i, n in enumerate(names):
            if n in names[:i]:
                raise fail("body and structure names must be unique", n, key=f"{paths[i]}.name")
        ice_names = [b.name for b in self.ice]
        st_names = [s.name for s in self.structure]
        seen: list[tuple[str, str, str]] = []
        for k, c in enumerate(self.contact):
            at = f"contact[{k}]"
            if c.ice not in ice_names:
                raise fail(_names("ice body", ice_names), c.ice, key=f"{at}.ice")
            if c.structure not in st_names:
                raise fail(_names("structure", st_names), c.structure, key=f"{at}.structure")
            name = c.name or f"{c.ice}-{c.structure}"
            if any(s[0] == name for s in seen):
                raise fail("contact names must be unique", name, key=f"{at}.name")
            if any(s[1:] == (c.ice, c.structure) for s in seen):
                raise fail(f"ice '{c.ice}' and structure '{c.structure}' already have a contact",
                           key=f"{at}.structure")
            seen.append((name, c.ice, c.structure))
        self._water_used()
        kinds = {s.name: s.kind for s in self.structure}
        ships = [s.name for s in self.structure if s.kind == "ship"]
        for k, s in enumerate(self.structure):
            if s.kind == "ship" and self.water is None:
                raise fail("a ship floats: the case needs a [water] section (density, level) for "
                           "its hydrostatics", s.kind, key=f"structure[{k}].kind")
            if s.attached_to is not None and s.attached_to not in ships:
                raise fail(_names("ship (kind = \"ship\")", ships), s.attached_to,
                           key=f"structure[{k}].attached_to")
        for k, m in enumerate(self.monitor):
            at = f"monitor[{k}]"
            if any(o.name == m.name for o in self.monitor[:k]):
                raise fail("monitor names must be unique", m.name, key=f"{at}.name")
            if m.structure not in kinds:
                raise fail(_names("structure", st_names), m.structure, key=f"{at}.structure")
            if kinds[m.structure] != "elastic":
                raise fail("monitors need an elastic structure", m.structure, key=f"{at}.structure")
        return self

    def _water_used(self) -> None:
        """Refuse a ``[water]`` (or a key of it) that nothing in the case feels: water acts on
        ice bodies (buoyancy, drag, added mass) and on ships (hydrostatics: density and level
        only)."""
        if self.water is None or self.ice:
            return
        if not any(s.kind == "ship" for s in self.structure):
            raise fail("[water] acts on ice bodies (buoyancy, drag) and on ships (kind = "
                       "\"ship\", hydrostatics); this case has neither, so nothing would feel "
                       "it: remove the [water] section (an elastic or rigid structure takes no "
                       "water load)", key="water")
        for key in ICE_ONLY_WATER_KEYS:
            if key in self.water.model_fields_set:
                raise fail(f"{key} acts on ice bodies only (a ship's hull feels the water's "
                           "density and level: its hydrostatics); this case has no ice: remove "
                           "it", getattr(self.water, key), key=f"water.{key}")
