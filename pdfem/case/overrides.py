"""Changing values of a case file: dotted-path overrides applied before validation.

An override is a dotted path into the TOML document and a value:
``{"ice.0.material.flexural_strength": 5e5, "run.end_time": 1e-3}``. List entries are numbered
from 0 (``ice.0`` is the first ``[[ice]]`` table); ``ice[0].material.flexural_strength``, the
form of the field paths in error messages, is the same path. :func:`override_case` sets each
value in the case's parsed data, a table missing on the way is created, and validates the
result with the schema, so every check and message of a case file applies to the changed
values (an unknown key is "unknown key" at its field). A path that cannot be followed (an
entry number beyond the list, a path through a value) is an :class:`~pdfem.errors.InputError`
naming the override's key.

The changed case's text (``Case.text``: stored in the results file, written as the case file
of each run of a sweep) is the data written back as TOML (:mod:`pdfem.case.toml_text`) after a
comment naming the original file and the overrides. Its file paths (a structure's ``.py`` or
``.msh`` mesh, a shape's ``mesh.file``: the schema's paths "relative to the case file") are
written absolute, so the text is a valid case file in any folder.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path
from typing import Any, Mapping

from pdfem.case.config import Case, resolve
from pdfem.case.loader import validate
from pdfem.case.toml_text import dumps, value_text
from pdfem.errors import InputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

_INDEX = re.compile(r"\[(\d+)\]")


def key_parts(key: str) -> list[str]:
    """The parts of a dotted path: ``"ice[0].dx"`` and ``"ice.0.dx"`` -> ``["ice", "0", "dx"]``."""
    return _INDEX.sub(r".\1", key.strip()).split(".")


def set_value(data: dict, key: str, value: Any, file: str | None = None) -> None:
    """Set the value at the dotted path ``key`` of the parsed case ``data`` (in place).

    Parameters
    ----------
    data
        A case file's data as ``tomllib`` parses it.
    key
        Dotted path (module docstring), e.g. ``ice.0.material.flexural_strength``.
    value
        The new value (a TOML value: number, string, bool, list, table; numpy numbers and
        arrays too); ``None`` removes the key (its default applies).
    file
        The case file, for messages.

    Raises
    ------
    InputError
        (field ``key``) If the path is empty, runs through a value, or names an entry beyond a
        list's end, or the value is not one a case file can hold.
    """
    if value is not None:
        try:
            value = tomllib.loads(f"v = {value_text(value)}")["v"]  # plain data, a copy
        except TypeError as exc:
            raise InputError(file, key, f"not a value a case file can hold ({exc})") from None
    parts = key_parts(key)
    if not all(parts):
        raise InputError(file, key, "not a dotted path of the case file; give section and keys "
                         "separated by dots, list entries by their number from 0, e.g. "
                         "ice.0.material.flexural_strength")
    node: Any = data
    for depth, part in enumerate(parts):
        here = ".".join(parts[:depth]) or "the case"
        last = depth == len(parts) - 1
        if isinstance(node, list):
            if not part.isdigit():
                raise InputError(file, key, f"{here} is a list of tables: give the number of an "
                                 f"entry (from 0) after it, e.g. {here}.0")
            if int(part) >= len(node):
                raise InputError(file, key, f"{here} has {len(node)} entr"
                                 f"{'y' if len(node) == 1 else 'ies'} (numbered from 0); there "
                                 f"is no entry {part}")
            part = int(part)
        elif not isinstance(node, dict):
            raise InputError(file, key, f"{here} is a value ({value_text(node)}), not a table: "
                             "nothing below it can be set")
        elif not last and part not in node:
            if parts[depth + 1].isdigit():
                raise InputError(file, key, f"the case has no {'.'.join(parts[:depth + 1])} "
                                 "entries to number")
            node[part] = {}
        if last and value is None:
            if isinstance(node, dict):
                node.pop(part, None)
            else:
                raise InputError(file, key, "a list entry cannot be removed; set the whole list")
        elif last:
            node[part] = value
        else:
            node = node[part]


def _absolute(path: str, directory: Path) -> str:
    p = Path(path)
    return path if p.is_absolute() else str(directory / p)


def anchor_paths(data: Any, directory: Path) -> None:
    """Make the case's file paths absolute (in place): a structure's ``mesh`` ending in ``.py``
    or ``.msh`` and a shape's ``mesh = {file = ...}``, the schema's paths relative to the case
    file (``directory``)."""
    if isinstance(data, list):
        for x in data:
            anchor_paths(x, directory)
        return
    if not isinstance(data, dict):
        return
    mesh = data.get("mesh")
    if isinstance(mesh, str) and mesh.endswith((".py", ".msh")):
        data["mesh"] = _absolute(mesh, directory)
    elif isinstance(mesh, dict) and isinstance(mesh.get("file"), str):
        mesh["file"] = _absolute(mesh["file"], directory)
    for v in data.values():
        anchor_paths(v, directory)


def override_case(case: Case, overrides: Mapping[str, Any]) -> Case:
    """The case with ``overrides`` applied to its file's data, validated again.

    Parameters
    ----------
    case
        A validated case (:func:`pdfem.case.load_case`).
    overrides
        ``{dotted path: value}`` (module docstring), applied in order.

    Returns
    -------
    Case
        The changed case: same file and directory (for messages and relative paths), its text
        the changed data as TOML with absolute file paths (module docstring).

    Raises
    ------
    InputError
        A path that cannot be followed (naming the key), or a changed value the schema refuses
        (naming the file and the field, as for a case file).
    """
    data = tomllib.loads(case.text)
    for key, value in overrides.items():
        set_value(data, key, value, case.file)
    anchor_paths(data, Path(case.directory))
    head = [f"# {case.file} with overrides:"] + \
        [f"#   {k} = {'(removed)' if v is None else value_text(v)}" for k, v in overrides.items()]
    text = "\n".join(head) + "\n\n" + dumps(data)
    return resolve(validate(data, case.file, Path(case.directory)), case.file, text,
                   Path(case.directory))
