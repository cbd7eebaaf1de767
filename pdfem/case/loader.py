"""Loading a case file: TOML text -> :class:`~pdfem.case.casefile.CaseFile` (validated by
pydantic) -> :class:`~pdfem.case.config.Case`.

The first validation error becomes one :class:`pdfem.errors.InputError` naming the file, the
dotted field path (``run.end_time``, ``ice[0].material.poisson_ratio``), the value and what
would be valid. Case files are data: nothing in them
is evaluated, but a ``.py`` model script named by a structure's ``mesh`` is executed
(Python code, :mod:`pdfem.meshing.runner`) when the run meshes the structure.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pydantic import ValidationError

from pdfem.case.casefile import CaseFile
from pdfem.case.config import Case, resolve
from pdfem.case.fields import ERROR_TYPE
from pdfem.case.toml_read import read_toml
from pdfem.errors import InputError


def field_path(loc: tuple[Any, ...]) -> str:
    """A pydantic error location as a dotted field path: ``("ice", 0, "dx")`` -> ``ice[0].dx``."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out


def input_error(exc: ValidationError, file: str) -> InputError:
    """The first error of a validation as an :class:`InputError` of ``file``."""
    e = exc.errors(include_url=False)[0]
    path = field_path(e["loc"])
    ctx = e.get("ctx") or {}
    if e["type"] == ERROR_TYPE:
        key = ctx.get("key")
        if key:
            path = f"{path}.{key}" if path else key
        return InputError(file, path or None, ctx["message"], ctx.get("value", ...))
    if e["type"] == "missing":
        return InputError(file, path or None, "this field is required")
    if e["type"] == "extra_forbidden":
        return InputError(file, path or None, "unknown key")
    if e["type"] == "value_error":
        return InputError(file, path or None, str(ctx.get("error", e["msg"])), e["input"])
    return InputError(file, path or None, e["msg"], e["input"])


def validate(data: dict, file: str, directory: Path) -> CaseFile:
    """Validate parsed TOML ``data`` (relative paths against ``directory``); raises InputError."""
    try:
        return CaseFile.model_validate(data, context={"directory": directory})
    except ValidationError as exc:
        raise input_error(exc, file) from None


def parse_case(text: str, file: str = "<string>", directory: Path | None = None) -> Case:
    """Parse and validate a case from TOML text.

    Parameters
    ----------
    text
        The TOML source.
    file
        Name used in error messages.
    directory
        Directory that relative paths in the case (meshes) are resolved against.

    Returns
    -------
    Case
        The validated case.

    Raises
    ------
    InputError
        For malformed TOML, unknown keys, wrong types or out-of-range values.
    """
    directory = Path(directory) if directory is not None else Path.cwd()
    return resolve(validate(read_toml(text, file), file, directory), file, text, directory)


def load_case(path: str | Path) -> Case:
    """Read and validate a case file (see :func:`parse_case`)."""
    p = Path(path)
    if not p.is_file():
        raise InputError(str(path), None, "no such case file")
    try:
        text = p.read_text(encoding="utf-8-sig")  # a byte-order mark (some editors) is dropped
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(str(path), None, f"cannot read the case file: {exc}") from None
    return parse_case(text, str(path), p.resolve().parent)
