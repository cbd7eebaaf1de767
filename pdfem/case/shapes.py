"""Shapes and regions of the case file: ``box``, ``cylinder``, ``sphere`` and (ice shapes only)
``mesh``, each validated into a :mod:`pdfem.geometry.shapes` object.

A shape table holds exactly one of these keys, e.g. ``{ box = { min = [0, 0, 0], max = [1, 1, 1] } }``.
Mesh files are found relative to the case file's directory (the validation context's
``directory``).
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Annotated, Any, ClassVar

from pydantic import (BeforeValidator, ConfigDict, Field, PrivateAttr, ValidationInfo,
                      model_validator)

from pdfem.case.fields import Name, Positive, Section, Vec3, Vector, fail, tidy_schema
from pdfem.geometry.shapes import Box, ClosedSurface, Cylinder, Sphere

Shape = Box | Cylinder | Sphere | ClosedSurface


class BoxShape(Section):
    """An axis-aligned box."""

    min: Annotated[Vec3, Vector("m")] = Field(
        description="Corner with the smallest coordinates (m). Required.")
    max: Annotated[Vec3, Vector("m")] = Field(
        description="Opposite corner, larger in every direction (m). Required.")

    def build(self) -> Box:
        """The geometry (raises ValueError if ``max`` is not above ``min``)."""
        return Box(self.min, self.max)


class CylinderShape(Section):
    """A solid circular cylinder."""

    base: Annotated[Vec3, Vector("m")] = Field(description="Centre of the base disc (m). Required.")
    axis: Annotated[Vec3, Vector()] = Field(
        description="Direction of the axis from the base (any length, not zero). Required.")
    radius: Annotated[float, Positive("m")] = Field(description="Radius (m). Required.")
    length: Annotated[float, Positive("m")] = Field(
        description="Length along the axis (m). Required.")

    def build(self) -> Cylinder:
        """The geometry (raises ValueError for a zero axis)."""
        return Cylinder(self.base, self.axis, self.radius, self.length)


class SphereShape(Section):
    """A solid sphere."""

    center: Annotated[Vec3, Vector("m")] = Field(description="Centre (m). Required.")
    radius: Annotated[float, Positive("m")] = Field(description="Radius (m). Required.")

    def build(self) -> Sphere:
        """The geometry."""
        return Sphere(self.center, self.radius)


class MeshShape(Section):
    """A solid bounded by a closed triangle surface read from a mesh file."""

    file: Name = Field(description="Surface mesh file (.msh, .stl, .obj, anything meshio reads), "
                                   "relative to the case file. Required.")
    group: Name | None = Field(
        None, description="Physical group of the file that holds the surface. "
                          "Default: every triangle of the file.")

    _path: Path = PrivateAttr()

    @model_validator(mode="after")
    def _exists(self, info: ValidationInfo) -> "MeshShape":
        path = Path(self.file)
        self._path = path if path.is_absolute() else directory(info) / path
        if not self._path.is_file():
            raise fail(f"no such mesh file ({self._path})", self.file, key="file")
        return self

    def build(self) -> ClosedSurface:
        """The geometry (raises ValueError if the surface is not closed)."""
        return ClosedSurface.from_file(self._path, self.group)


def directory(info: ValidationInfo) -> Path:
    """The directory that relative paths are resolved against (validation context)."""
    return Path((info.context or {}).get("directory", Path.cwd()))


def _one_key_schema(schema: dict[str, Any]) -> None:
    tidy_schema(schema)
    schema.update(minProperties=1, maxProperties=1)


class RegionSection(Section):
    """A region: exactly one of ``box``, ``cylinder`` or ``sphere``."""

    model_config = ConfigDict(json_schema_extra=_one_key_schema)

    box: BoxShape | None = Field(
        None, description="A box `{min, max}` (m). Default: none (give exactly one shape).")
    cylinder: CylinderShape | None = Field(
        None, description="A cylinder `{base, axis, radius, length}` (m). "
                          "Default: none (give exactly one shape).")
    sphere: SphereShape | None = Field(
        None, description="A sphere `{center, radius}` (m). Default: none (give exactly one shape).")
    _geometry: Any = PrivateAttr(None)
    extra_keys: ClassVar[tuple[str, ...]] = ()  # keys allowed beside the shape


    @model_validator(mode="before")
    @classmethod
    def _known_keys(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            raise fail("expected a table ({ key = value, ... })", data)
        kinds = [k for k in cls.keys() if k not in cls.extra_keys]
        given = [k for k in kinds if k in data]
        extra = sorted(set(data) - set(kinds) - set(cls.extra_keys))
        if len(given) != 1 or extra:
            what = f"unknown key '{extra[0]}'; " if extra else ""
            raise fail(what + "expected exactly one of " + ", ".join(kinds), data)
        return data

    @model_validator(mode="after")
    def _build(self) -> "RegionSection":
        kind = next(k for k in self.keys()
                    if k not in self.extra_keys and getattr(self, k) is not None)
        try:
            self._geometry = getattr(self, kind).build()
        except ValueError as exc:
            raise fail(str(exc), key=kind) from None
        return self

    @property
    def geometry(self) -> Shape:
        """The validated :mod:`pdfem.geometry.shapes` object."""
        return self._geometry


class ShapeSection(RegionSection):
    """A body's shape: exactly one of ``box``, ``cylinder``, ``sphere`` or ``mesh``."""

    mesh: MeshShape | None = Field(
        None, description="A closed surface mesh `{file, group}`. "
                          "Default: none (give exactly one shape).")


_REGION_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_+\-]*\Z")


def _region_name_check(v: Any) -> str:
    if not isinstance(v, str) or not _REGION_NAME.match(v):
        raise fail("expected a name of letters, digits, '_', '+', '-' (no dots or spaces): it "
                   "names the history loads/<body>.<name> of the results", v)
    return v


#: The name of a fixed or prescribed region (letters, digits, ``_ + -``).
RegionName = Annotated[str, Field(pattern="^" + _REGION_NAME.pattern[:-2] + "$"),
                       BeforeValidator(_region_name_check)]


def _named_schema(schema: dict[str, Any]) -> None:
    tidy_schema(schema)
    schema.update(minProperties=1, maxProperties=2)


class NamedRegionSection(RegionSection):
    """A region with an optional name: exactly one of ``box``, ``cylinder`` or ``sphere``, and
    ``name``."""

    model_config = ConfigDict(json_schema_extra=_named_schema)
    extra_keys: ClassVar[tuple[str, ...]] = ("name",)

    name: RegionName | None = Field(
        None, description="Name of the region's reaction history `loads/<body>.<name>` (letters, "
                          "digits, _ + -), unique in the body. Default: fixed1, fixed2, ... by "
                          "position in the list.")


def _path_check(v: Any) -> tuple[tuple[float, float, float, float], ...]:
    if not isinstance(v, list) or not v:
        raise fail("expected a list of rows [t, ux, uy, uz] (s, m)", v)
    rows = []
    for k, row in enumerate(v):
        if not (isinstance(row, list) and len(row) == 4 and all(
                isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)
                for c in row)):
            raise fail(f"row {k}: expected four finite numbers [t, ux, uy, uz] (s, m)", row)
        if rows and row[0] <= rows[-1][0]:
            raise fail(f"row {k}: the times must increase strictly (t = {row[0]:g} s after "
                       f"t = {rows[-1][0]:g} s)", row)
        rows.append(tuple(float(c) for c in row))
    if rows[0][0] < 0.0:
        raise fail("the first time must be >= 0 s", v[0])
    return tuple(rows)


#: A displacement path ``[[t, ux, uy, uz], ...]`` (s, m): piecewise linear, t strictly
#: increasing, first t >= 0; the first point's displacement before it, the last one's after.
MotionPath = Annotated[tuple[tuple[float, float, float, float], ...],
                       BeforeValidator(_path_check)]
