"""Reading a case file's TOML text into tables, every failure an :class:`~pdfem.errors.InputError`
naming the file.

Two failures of the TOML reader need help to read as bad input: a key given twice, which
``tomllib`` reports by line and column only ("Cannot overwrite a value (at line 3, column 16)")
and which is reported here by its dotted path (``run.end_time``, ``ice[1].dx``); and tables or
arrays nested so deeply that the reader's recursion overflows (``RecursionError``; a case file
nests a few levels).
"""

from __future__ import annotations

import ast
import re
import sys
from typing import Any

from pdfem.errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

_AT = re.compile(r"\(at line (\d+), column (\d+)\)$")
_TWICE = re.compile(r"^Cannot declare (\(.*\)) twice")
_PART = r"""(?:[A-Za-z0-9_-]+|"(?:[^"\\]|\\.)*"|'[^']*')"""
_KEY = re.compile(rf"\s*({_PART}(?:\s*\.\s*{_PART})*)\s*=")
_HEADER = re.compile(rf"\s*(\[\[?)\s*({_PART}(?:\s*\.\s*{_PART})*)\s*\]\]?\s*(#.*)?$")


def read_toml(text: str, file: str) -> dict[str, Any]:
    """The tables of the TOML ``text`` of ``file``.

    Raises
    ------
    InputError
        Not valid TOML (a key given twice is named by its path), or nested too deeply to read.
    """
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise _decode_error(str(exc), text, file) from None
    except RecursionError:
        raise InputError(file, None, "not valid TOML for pdfem: tables or arrays nested too "
                         "deeply for the TOML reader (a case file nests a few levels, e.g. "
                         "[[ice]] > shape > box > min)") from None


def _decode_error(message: str, text: str, file: str) -> InputError:
    at = _AT.search(message)
    twice = _TWICE.match(message)
    if at and twice:
        parts = ast.literal_eval(twice[1])
        return InputError(file, ".".join(map(str, parts)), f"the table is declared twice (the "
                          f"second time at line {at[1]}); declare each table once")
    if at and message.startswith("Cannot overwrite a value"):
        found = _statement_key(text, int(at[1]), int(at[2]))
        if found:
            return InputError(file, found[0], f"the key is given twice (the second time at line "
                              f"{found[1]}); give each key once")
    return InputError(file, None, f"not valid TOML: {message}")


def _parts(dotted: str) -> list[str]:
    """The parts of a TOML dotted key (bare or quoted), e.g. ``a."b c"`` -> ``["a", "b c"]``."""
    table = tomllib.loads(f"{dotted} = 0")
    parts = []
    while isinstance(table, dict):
        (name, table), = table.items()
        parts.append(name)
    return parts


def _statement_key(text: str, line: int, column: int) -> tuple[str, int] | None:
    """The dotted path (with its table) and the first line of the key/value statement that ends
    at ``line``, ``column`` (1-based; where ``tomllib`` reports an overwritten value): the
    statement starts on the nearest line from which the text up to there parses alone."""
    lines = text.splitlines(keepends=True)
    if not 1 <= line <= len(lines):
        return None
    end = sum(len(s) for s in lines[:line - 1]) + column - 1
    for start in range(line - 1, -1, -1):
        fragment = "".join(lines[start:])[:end - sum(len(s) for s in lines[:start])]
        try:
            parsed = tomllib.loads(fragment)
        except (tomllib.TOMLDecodeError, RecursionError):
            continue
        key = _KEY.match(fragment)
        if not parsed or not key:
            return None
        return _table_path(lines[:start]) + ".".join(_parts(key[1])), start + 1
    return None


def _table_path(before: list[str]) -> str:
    """The path of the table the lines after ``before`` are in, with a dot: ``run.``,
    ``ice[1].material.``; ``""`` at the top level."""
    header, arrays = None, {}
    for text in before:
        m = _HEADER.match(text)
        if m:
            parts = _parts(m[2])
            if m[1] == "[[":
                arrays[parts[0]] = arrays.get(parts[0], -1) + 1
            header = parts
    if header is None:
        return ""
    first = header[0] + (f"[{arrays[header[0]]}]" if header[0] in arrays else "")
    return ".".join([first, *header[1:]]) + "."
