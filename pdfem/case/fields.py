"""Field types of the case schema: checked numbers, vectors, names and flags, and the base class
of every section.

Each type is a pydantic type (so the JSON Schema shows it: ``number`` with its bounds, an array
of three numbers, an enum...) preceded by a check of our own that gives the message a user
should read ("expected a finite number in s", "must be > 0 s"). Units and bounds are
``Annotated`` metadata: ``Annotated[float, Number("s", gt=0)]``, ``Annotated[Vec3, Vector("m")]``,
``Annotated[int, Whole(0)]``. A check fails with
:func:`fail`, whose error :mod:`pdfem.case.loader` turns into :class:`pdfem.errors.InputError`.
TOML gives no nulls, so ``None`` in a field means "not given".
"""

from __future__ import annotations

import math
import re
from typing import Annotated, Any, ClassVar, Iterator, Literal

from annotated_types import GroupedMetadata, Interval
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, model_validator
from pydantic_core import PydanticCustomError

#: Error type of the checks here (the loader reads its ``message``, ``key`` and ``value``).
ERROR_TYPE = "pdfem"


def fail(message: str, value: Any = ..., key: str | None = None) -> PydanticCustomError:
    """An error for the loader: ``message`` about ``value``, at the validated location plus ``key``.

    Parameters
    ----------
    message
        What is wrong and what would be valid.
    value
        The offending value (``...``: none shown).
    key
        Dotted path below the location being validated (a model validator naming one of its
        fields), if any.
    """
    ctx: dict[str, Any] = {"message": message}
    if value is not ...:
        ctx["value"] = value
    if key:
        ctx["key"] = key
    return PydanticCustomError(ERROR_TYPE, "{message}", ctx)


def _in(unit: str) -> str:
    return f" in {unit}" if unit else ""


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _number_check(unit: str, gt: float | None, ge: float | None, lt: float | None, le: float | None):
    def check(v: Any) -> float:
        if not _is_number(v):
            raise fail(f"expected a finite number{_in(unit)}", v)
        low, low_open = (gt, True) if gt is not None else (ge, False)
        high, high_open = (lt, True) if lt is not None else (le, False)
        bad = (low is not None and (v <= low if low_open else v < low)) or \
              (high is not None and (v >= high if high_open else v > high))
        if bad:
            lo = "" if low is None else (f"> {low:g}" if low_open else f">= {low:g}")
            hi = "" if high is None else (f"< {high:g}" if high_open else f"<= {high:g}")
            rng = " and ".join(s for s in (lo, hi) if s)
            raise fail(f"must be {rng}{' ' + unit if unit else ''}", v)
        return float(v)
    return check


class Number(GroupedMetadata):
    """Metadata of a finite number (an int is taken as a float) within bounds, in ``unit``:
    ``Annotated[float, Number("s", gt=0)]``."""

    def __init__(self, unit: str = "", *, gt: float | None = None, ge: float | None = None,
                 lt: float | None = None, le: float | None = None):
        self.unit, self.bounds = unit, (gt, ge, lt, le)

    def __iter__(self) -> Iterator[Any]:
        gt, ge, lt, le = self.bounds
        yield Interval(gt=gt, ge=ge, lt=lt, le=le)
        yield BeforeValidator(_number_check(self.unit, gt, ge, lt, le))


def Positive(unit: str = "") -> Number:
    """Metadata of a finite number > 0 in ``unit``."""
    return Number(unit, gt=0.0)


def _vector_check(unit: str, positive: bool):
    def check(v: Any) -> tuple[float, float, float]:
        if not (isinstance(v, (list, tuple)) and len(v) == 3 and all(_is_number(c) for c in v)
                and (not positive or all(c > 0 for c in v))):
            what = "three finite numbers > 0" if positive else "three finite numbers"
            raise fail(f"expected {what} [x, y, z]{_in(unit)}", v)
        return (float(v[0]), float(v[1]), float(v[2]))
    return check


#: Three floats.
Vec3 = tuple[float, float, float]

_Above0 = Annotated[float, Interval(gt=0.0)]

#: Three floats > 0 (the JSON Schema shows the bound on each).
PositiveVec3 = tuple[_Above0, _Above0, _Above0]


class Vector(GroupedMetadata):
    """Metadata of three finite numbers ``[x, y, z]`` in ``unit``: ``Annotated[Vec3, Vector("m")]``;
    ``positive``: each > 0 (``Annotated[PositiveVec3, Vector("m", positive=True)]``)."""

    def __init__(self, unit: str = "", positive: bool = False):
        self.unit, self.positive = unit, positive

    def __iter__(self) -> Iterator[Any]:
        yield BeforeValidator(_vector_check(self.unit, self.positive))


def _name_check(v: Any) -> str:
    if not isinstance(v, str) or not v:
        raise fail("expected a non-empty string", v)
    return v


#: A non-empty string (a name, a mesh group, a file).
Name = Annotated[str, Field(min_length=1), BeforeValidator(_name_check)]


_IDENTIFIER = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9_.-]*\Z")


def _identifier_check(v: Any) -> str:
    if not isinstance(v, str) or not _IDENTIFIER.match(v):
        raise fail("expected a name of letters, digits, '_', '-' and '.' (not first; no spaces, "
                   "slashes or other characters): it names files and groups of the results", v)
    return v


#: A name that becomes a file or HDF5 group name (ice bodies, structures, contacts, monitors):
#: letters, digits, ``_``, ``-`` and ``.`` (not first).
Identifier = Annotated[str, Field(pattern="^" + _IDENTIFIER.pattern[:-2] + "$"),
                       BeforeValidator(_identifier_check)]


def _text_check(v: Any) -> str:
    if not isinstance(v, str):
        raise fail("expected a string", v)
    return v


#: Any string, empty included.
Text = Annotated[str, BeforeValidator(_text_check)]


def _choice_check(choices: tuple[str, ...]):
    def check(v: Any) -> str:
        _name_check(v)
        if v not in choices:
            raise fail("must be one of " + ", ".join(f'"{c}"' for c in choices), v)
        return v
    return check


def Choice(*choices: str) -> Any:
    """The type "one of the strings ``choices``" (declare it once, as a module-level alias)."""
    return Annotated[Literal[choices], BeforeValidator(_choice_check(choices))]


def _boolean_check(v: Any) -> bool:
    if not isinstance(v, bool):
        raise fail("expected true or false", v)
    return v


#: ``true`` or ``false``.
Boolean = Annotated[bool, BeforeValidator(_boolean_check)]


def _whole_check(low: int, note: str):
    def check(v: Any) -> int:
        if isinstance(v, bool) or not isinstance(v, int) or v < low:
            raise fail(f"expected a whole number >= {low} {note}".rstrip(), v)
        return v
    return check


class Whole(GroupedMetadata):
    """Metadata of a whole number >= ``low`` (``note`` explains a special value, e.g.
    "(0 = automatic)"): ``Annotated[int, Whole(0)]``."""

    def __init__(self, low: int, note: str = ""):
        self.low, self.note = low, note

    def __iter__(self) -> Iterator[Any]:
        yield Interval(ge=self.low)
        yield BeforeValidator(_whole_check(self.low, self.note))


def _names_check(v: Any) -> tuple[str, ...]:
    if isinstance(v, str):
        v = [v]
    if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
        raise fail("expected a list of group names", v)
    return tuple(v)


#: A list of names (a single name is taken as a list of one).
Names = Annotated[tuple[str, ...], BeforeValidator(_names_check)]


def _tables_check(v: Any) -> list:
    if isinstance(v, dict):
        v = [v]
    if not isinstance(v, list):
        raise fail("expected a list of tables", v)
    return v


def Tables(section: type) -> Any:
    """A list of tables (``[[section]]`` or ``key = [ {...}, ... ]``); one table is a list of one."""
    return Annotated[tuple[section, ...], BeforeValidator(_tables_check)]


def tidy_schema(schema: dict[str, Any]) -> None:
    """Drop what only clutters a table's JSON Schema: the titles pydantic makes from field names
    ("Dx"), and ``null`` (TOML has none: a key that is not given is absent)."""
    for prop in schema.get("properties", {}).values():
        prop.pop("title", None)
        if "default" in prop and prop["default"] is None:
            del prop["default"]
        options = [o for o in prop.get("anyOf", ()) if o != {"type": "null"}]
        if len(options) == 1:
            del prop["anyOf"]
            prop.update(options[0])


class Section(BaseModel):
    """A TOML table: frozen, unknown keys refused (the message lists the keys allowed here)."""

    model_config = ConfigDict(frozen=True, extra="forbid", json_schema_extra=tidy_schema)

    #: ``(key, other, message)``: ``key`` has an effect only with ``other`` (a field whose
    #: ``None`` means "not given"); given without it, it is refused with ``message``.
    needs: ClassVar[tuple[tuple[str, str, str], ...]] = ()

    @classmethod
    def keys(cls) -> list[str]:
        """The TOML keys of this table, in declaration order."""
        return [f.alias or name for name, f in cls.model_fields.items()]

    @model_validator(mode="before")
    @classmethod
    def _known_keys(cls, data: Any) -> Any:
        if not isinstance(data, dict):
            raise fail("expected a table ({ key = value, ... })", data)
        unknown = [k for k in data if k not in cls.keys()]
        if unknown:
            raise fail("unknown key; the keys allowed here are: " + ", ".join(sorted(cls.keys())),
                       key=str(unknown[0]))
        return data

    @model_validator(mode="after")
    def _needed(self) -> "Section":
        for key, other, message in self.needs:
            if key in self.model_fields_set and getattr(self, other) is None:
                raise fail(message, getattr(self, key), key=key)
        return self
