"""The grid of a parameter study: which values each key takes, the runs they make, their names.

A grid is an ordered mapping ``{dotted key: [values]}`` (keys as in
:mod:`pdfem.case.overrides`); its runs are the cartesian product of the values, the first key
varying slowest. Each run is named by its values, ``speed=0.5__thickness=0.2``: a key is
shortened to its last part (``ice.0.material.flexural_strength`` -> ``flexural_strength``), or
to as many of its last parts as tell it from the other keys, and a value is written as in TOML
(floats with every digit, lists without brackets); characters other than letters, digits and
``. , + - _`` become ``_``. The name depends on nothing but the keys and values, so a sweep run
again finds its runs under the same names.

On the command line a key's values are one option, ``--set KEY=V1,V2,...``
(:func:`parse_set`): each value is read as a TOML value (``0.5``, ``true``, ``[0, 0, -1]``,
``"text"``) or, when it is not one, as a string (``--set run.pd_loop=pairs,full_family``);
commas inside brackets or quotes do not split.
"""

from __future__ import annotations

import itertools
import re
import sys
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

from pdfem.case.overrides import key_parts
from pdfem.case.toml_text import value_text
from pdfem.errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

_UNSAFE = re.compile(r"[^A-Za-z0-9.,+_-]")


@dataclass(frozen=True)
class GridRun:
    """One run of a grid: its name (its folder under ``runs/``) and its overrides."""

    name: str
    values: dict[str, Any]


def _split_values(text: str) -> list[str]:
    """``text`` split at the commas outside brackets, braces and quotes."""
    parts, depth, quote, start = [], 0, "", 0
    for i, c in enumerate(text):
        if quote:
            quote = "" if c == quote and text[i - 1] != "\\" else quote
        elif c in "\"'":
            quote = c
        elif c in "[{":
            depth += 1
        elif c in "]}":
            depth -= 1
        elif c == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    parts.append(text[start:])
    return [p.strip() for p in parts]


def parse_value(text: str) -> Any:
    """A ``--set`` value: a TOML value, else the text as a string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def parse_set(option: str) -> tuple[str, list[Any]]:
    """One ``--set KEY=V1,V2,...`` option: the key and its values.

    Raises
    ------
    InputError
        (field ``--set``) If there is no ``=``, no key or an empty value.
    """
    key, eq, values = option.partition("=")
    key = key.strip()
    if not eq or not key:
        raise InputError(None, "--set", "give KEY=V1,V2,... with KEY a dotted path of the case "
                         "file, e.g. --set ice.0.material.flexural_strength=4e5,6e5", option)
    texts = _split_values(values)
    if any(not t for t in texts):
        raise InputError(None, f"--set {key}", "a value is empty; give the values separated by "
                         "commas, e.g. 0.5,1.0", values)
    return key, [parse_value(t) for t in texts]


def short_keys(keys: Sequence[str]) -> dict[str, str]:
    """Each key's name in run names: its fewest last parts that tell it from the other keys
    and do not start with an entry number."""
    parts = {k: key_parts(k) for k in keys}
    out = {}
    for k, p in parts.items():
        for n in range(1, len(p) + 1):
            tail = p[-n:]
            if tail[0].isdigit() and n < len(p):
                continue
            if not any(q[-n:] == tail for other, q in parts.items() if other != k):
                break
        out[k] = ".".join(tail)
    return out


def value_label(v: Any) -> str:
    """A value as written in run names: TOML text, lists without brackets, strings bare."""
    if isinstance(v, str):
        text = v
    elif isinstance(v, (list, tuple)):
        text = ",".join(value_label(x) for x in v)
    else:
        text = value_text(v)
    return _UNSAFE.sub("_", text)


def grid_runs(grid: Mapping[str, Sequence[Any]]) -> list[GridRun]:
    """The runs of a grid: the cartesian product of its values, first key slowest.

    Parameters
    ----------
    grid
        ``{dotted key: values}``, at least one key, each with at least one value.

    Returns
    -------
    list of GridRun
        In grid order; task ``i`` of a job array runs entry ``i``.

    Raises
    ------
    InputError
        No key, a key without values, a key given twice (as ``ice.0.dx`` and ``ice[0].dx``),
        or two values of a key that give the same run name.
    """
    if not grid:
        raise InputError(None, "--set", "give at least one key and its values: --set "
                         "KEY=V1,V2,...")
    seen: dict[tuple[str, ...], str] = {}
    for key, values in grid.items():
        if isinstance(values, (str, bytes)) or not isinstance(values, Sequence) or not values:
            raise InputError(None, f"--set {key}", "give a list of at least one value", values)
        same = seen.setdefault(tuple(key_parts(key)), key)
        if same != key:
            raise InputError(None, f"--set {key}", f"the same key as {same}; give each key once")
    short = short_keys(list(grid))
    for key, values in grid.items():
        labels = [value_label(v) for v in values]
        for i, label in enumerate(labels):
            if label in labels[:i]:
                raise InputError(None, f"--set {key}", f"two values give the same run name "
                                 f"({short[key]}={label}); give each value once", values[i])
    runs = []
    for combo in itertools.product(*grid.values()):
        values = dict(zip(grid, combo))
        name = "__".join(f"{short[k]}={value_label(v)}" for k, v in values.items())
        runs.append(GridRun(name, values))
    return runs
