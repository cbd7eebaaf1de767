"""Parameters of the model scripts: declared as a table, validated by a pydantic model.

A model script declares ``PARAMETERS: dict[str, tuple[default, unit, description]]``; the type
of the default (bool, int, float or str) is the parameter's type. :func:`parameter_model` turns
such a table into a pydantic model (the same mechanism that validates case files,
:mod:`pdfem.case`): unknown names are refused, floats must be finite (an int is taken as a
float), and every error becomes a :class:`ModelParameterError` naming the parameter.
:func:`check_parameters` validates typed values (from a case file or Python),
:func:`coerce_parameters` strings from the command line (``--set key=value``, :func:`parse_set`).

The ``require_*`` checks are for a model's own ranges and consistency rules, and
:func:`require_element_budget` refuses an element size that would make gmsh run for hours.
"""

from __future__ import annotations

import math
from typing import Annotated, Any

import numpy as np
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError, create_model
from pydantic_core import PydanticCustomError

from pdfem.errors import InputError

#: Most surface triangles a model may ask gmsh for (see :func:`require_element_budget`).
MAX_SURFACE_TRIANGLES = 4_000_000

_TYPE_NAMES = {bool: "a boolean (true/false)", int: "an integer", float: "a number", str: "a string"}


class ModelParameterError(InputError, ValueError):
    """A model parameter that is unknown, of the wrong type, out of range or inconsistent.

    Parameters
    ----------
    param
        Name of the offending parameter (as in the model's ``PARAMETERS``), or ``"model"``
        for a model name or path that cannot be resolved.
    value
        The offending value.
    message
        What is wrong and what would be valid, as a sentence.
    """

    def __init__(self, param: str, value: Any, message: str):
        self.param = param
        super().__init__(None, param, message, value)


def _parse_bool(text: str) -> bool:
    t = text.strip().lower()
    if t in ("1", "true", "yes", "on"):
        return True
    if t in ("0", "false", "no", "off"):
        return False
    raise ValueError(text)


def _wrong(kind: type, value: Any, message: str | None = None) -> PydanticCustomError:
    return PydanticCustomError("pdfem_parameter", "{message}",
                               {"message": message or f"must be {_TYPE_NAMES[kind]}", "value": value})


def _value_check(kind: type, from_text: bool):
    """A check of one parameter of type ``kind``; ``from_text``: a string is parsed first."""
    def check(value: Any) -> Any:
        if from_text and isinstance(value, str) and kind is not str:
            try:
                value = _parse_bool(value) if kind is bool else kind(value.strip())
            except ValueError:
                raise _wrong(kind, value) from None
        if kind is float:
            if isinstance(value, (bool, np.bool_)) or \
                    not isinstance(value, (int, float, np.integer, np.floating)):
                raise _wrong(kind, value)
            value = float(value)
            if not math.isfinite(value):
                raise _wrong(kind, value, "must be a finite number")
        elif kind is int:
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
                raise _wrong(kind, value)
            value = int(value)
        elif kind is bool:
            if not isinstance(value, (bool, np.bool_)):
                raise _wrong(kind, value)
            value = bool(value)
        elif not isinstance(value, str):
            raise _wrong(kind, value)
        return value
    return check


def parameter_model(parameters: dict[str, tuple], name: str = "ModelParameters",
                    from_text: bool = False) -> type[BaseModel]:
    """The pydantic model of a ``PARAMETERS`` table.

    Parameters
    ----------
    parameters
        name -> (default, unit, description); the default's type is the parameter's type.
    name
        Title of the model (e.g. the model script's name).
    from_text
        Accept strings for non-string parameters and parse them (``--set`` values; booleans as
        true/false, yes/no, on/off, 1/0).

    Returns
    -------
    type[pydantic.BaseModel]
        A model with one field per parameter (its default, and a description with the unit);
        unknown names are refused.
    """
    fields: dict[str, Any] = {}
    for key, (default, unit, description) in parameters.items():
        kind = type(default)
        if kind not in _TYPE_NAMES:
            raise TypeError(f"parameter {key!r}: the default must be a bool, int, float or str")
        text = f"{description} ({unit})" if unit and unit != "-" else description
        fields[key] = (Annotated[kind, BeforeValidator(_value_check(kind, from_text))],
                       Field(default, description=f"{text}. Default: {default!r}."))
    return create_model(name, __config__=ConfigDict(extra="forbid", frozen=True), **fields)


def _validate(parameters: dict[str, tuple], given: dict[str, Any], from_text: bool) -> dict[str, Any]:
    try:
        return parameter_model(parameters, from_text=from_text).model_validate(given).model_dump()
    except ValidationError as exc:
        errors = exc.errors(include_url=False)
        unknown = [e for e in errors if e["type"] == "extra_forbidden"]
        if unknown:
            key = str(unknown[0]["loc"][0])
            raise ModelParameterError(key, given[key], "unknown parameter; valid parameters are: "
                                      + ", ".join(sorted(parameters))) from None
        e = errors[0]
        ctx = e.get("ctx") or {}
        raise ModelParameterError(str(e["loc"][0]), ctx.get("value", e["input"]),
                                  ctx.get("message", e["msg"])) from None


def check_parameters(parameters: dict[str, tuple], given: dict[str, Any]) -> dict[str, Any]:
    """Fill in defaults and check the names and types of a model's parameters.

    Parameters
    ----------
    parameters
        The model's ``PARAMETERS``: name -> (default, unit, description). The default's type
        (bool, int, float or str) is the parameter's type; an int is accepted for a float.
    given
        The values given by the caller (already typed; see :func:`coerce_parameters` for
        strings from the command line).

    Returns
    -------
    dict
        Every parameter with its value (given or default), floats as ``float``.

    Raises
    ------
    ModelParameterError
        An unknown name (the message lists the valid ones), a value of the wrong type, or a
        float that is not finite.
    """
    return _validate(parameters, given, from_text=False)


def coerce_parameters(parameters: dict[str, tuple], raw: dict[str, Any]) -> dict[str, Any]:
    """Convert ``--set`` values (strings) to the types of the parameters' defaults.

    Parameters
    ----------
    parameters
        The model's ``PARAMETERS``.
    raw
        name -> value; strings are parsed as the default's type (float, int, bool: true/false,
        yes/no, on/off, 1/0; str as is); other values must have the parameter's type.

    Returns
    -------
    dict
        The typed values (only the given names; defaults are filled in by the model).

    Raises
    ------
    ModelParameterError
        An unknown name (listing the valid names) or a value that does not parse.
    """
    typed = _validate(parameters, raw, from_text=True)
    return {key: typed[key] for key in raw}


def parse_set(items: list[str] | tuple[str, ...]) -> dict[str, str]:
    """Split command-line ``key=value`` strings into a dict (later keys win).

    Raises
    ------
    ModelParameterError
        An item without ``=`` or with an empty key.
    """
    out: dict[str, str] = {}
    for item in items:
        key, sep, value = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ModelParameterError("--set", item, "expected key=value")
        out[key] = value.strip()
    return out


def require(condition: bool, param: str, value: Any, message: str) -> None:
    """Raise :class:`ModelParameterError` ``(param, value, message)`` unless ``condition``."""
    if not condition:
        raise ModelParameterError(param, value, message)


def require_positive(params: dict[str, Any], *names: str) -> None:
    """Check that each named parameter is > 0 (raises :class:`ModelParameterError`)."""
    for name in names:
        require(params[name] > 0, name, params[name], "must be > 0")


def require_range(params: dict[str, Any], name: str, low: float | None = None, high: float | None = None,
                  *, low_open: bool = False, high_open: bool = False, unit: str = "") -> None:
    """Check ``low <= params[name] <= high`` (``<`` for an open end); ``None`` means unbounded."""
    v = params[name]
    u = f" {unit}" if unit else ""
    if low is not None and (v <= low if low_open else v < low):
        raise ModelParameterError(name, v, f"must be {'>' if low_open else '>='} {low:g}{u}")
    if high is not None and (v >= high if high_open else v > high):
        raise ModelParameterError(name, v, f"must be {'<' if high_open else '<='} {high:g}{u}")


def require_choice(params: dict[str, Any], name: str, choices: tuple[str, ...]) -> None:
    """Check that a string parameter is one of ``choices``."""
    require(params[name] in choices, name, params[name], "must be one of: " + ", ".join(choices))


def require_element_budget(area: float, element_size: float, what: str) -> None:
    """Refuse an ``element_size`` that would cover ``area`` with too many surface triangles.

    Guards against a mistyped element size that would take gmsh hours and all the memory.

    Parameters
    ----------
    area
        Surface area to be meshed, m^2 (an estimate is enough).
    element_size
        Target element edge length, m.
    what
        The object, for the message (e.g. ``"this panel"``).

    Raises
    ------
    ModelParameterError
        (``param == "element_size"``) more than :data:`MAX_SURFACE_TRIANGLES` triangles of
        that size (area 0.433 h^2 each) would be needed.
    """
    tris = area / (0.433 * element_size * element_size)
    require(tris < MAX_SURFACE_TRIANGLES, "element_size", element_size,
            f"too small for {what} (about {tris:.2g} surface triangles; at most {MAX_SURFACE_TRIANGLES:.0e})")
