"""Case data back to TOML text: the case file of a case changed in Python or by a sweep.

:func:`dumps` writes the plain data a case file parses to (tables, arrays, strings, numbers,
booleans) so that ``tomllib.loads(dumps(data)) == data``: top-level values first, then each
table as a ``[section]`` and each array of tables as ``[[section]]`` entries, everything below
a section as inline values (``shape = { box = { min = [0.0, 0.0, 0.0], ... } }``), as the case
files in ``models/`` are written. Floats keep every digit (``repr``), so a value read back is
the same number.
"""

from __future__ import annotations

import json
import math
import numbers
import re
from typing import Any

import numpy as np

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


def _key(k: str) -> str:
    """A key, bare if TOML allows it, else quoted."""
    return k if _BARE_KEY.match(k) else json.dumps(k, ensure_ascii=False)


def _float_text(x: float) -> str:
    """The shorter of ``repr(x)`` and the shortest exponent form that reads back as ``x``
    (``4.1e+09`` rather than ``4100000000.0``)."""
    for digits in range(17):
        e = f"{x:.{digits}e}"
        if float(e) == x:
            break
    r = repr(x)
    return e if len(e) < len(r) else r


def value_text(v: Any) -> str:
    """One TOML value written inline.

    Parameters
    ----------
    v
        A bool, an integer, a real number, a string, a list or tuple, or a dict with string
        keys (numpy scalars count as numbers; arrays are written through their ``tolist``).

    Raises
    ------
    TypeError
        For anything else (a date, ``None``): TOML has no such value in a case file.
    """
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, numbers.Integral):
        return str(int(v))
    if isinstance(v, numbers.Real):
        x = float(v)
        if math.isnan(x):
            return "nan"
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
        return _float_text(x)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)  # JSON's escapes are TOML basic-string escapes
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {value_text(x)}" for k, x in v.items()) + " }" \
            if v else "{}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(value_text(x) for x in v) + "]"
    if isinstance(v, np.ndarray):
        return value_text(v.tolist())
    raise TypeError(f"{type(v).__name__} is not a value of a case file: {v!r}")


def _is_table_array(v: Any) -> bool:
    return isinstance(v, (list, tuple)) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def _lines(table: dict) -> list[str]:
    return [f"{_key(k)} = {value_text(v)}" for k, v in table.items()]


def dumps(data: dict[str, Any]) -> str:
    """The TOML text of a case's data (module docstring).

    Parameters
    ----------
    data
        A dict as ``tomllib`` parses a case file to (section name -> table, or -> list of
        tables).

    Returns
    -------
    str
        TOML text, ending with a newline, that parses back to ``data``.
    """
    top = {k: v for k, v in data.items() if not isinstance(v, dict) and not _is_table_array(v)}
    out = _lines(top)
    for k, v in data.items():
        if isinstance(v, dict):
            out += ["", f"[{_key(k)}]", *_lines(v)]
        elif _is_table_array(v):
            for entry in v:
                out += ["", f"[[{_key(k)}]]", *_lines(entry)]
    return "\n".join(out).lstrip("\n") + "\n"
