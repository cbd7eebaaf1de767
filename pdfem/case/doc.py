"""The case-file reference as a markdown table, generated from the schema (the README's
"Case files" table is this text: ``pdfem schema --markdown``; tests/case/test_schema.py keeps the two
the same).

Every description in the schema reads "meaning (unit). Default: ..." or "meaning. Required.";
the table splits it into its "meaning (unit)" and "default" columns. Sub-tables are flattened
into dotted keys (``material.density``), lists of tables into ``key[].sub``; a shape or region
(exactly one of ``box``, ``cylinder``, ...) stays one row.
"""

from __future__ import annotations

import types
import typing
from typing import Any, Iterator

from pydantic.fields import FieldInfo

from pdfem.case.casefile import CaseFile
from pdfem.case.fields import Section
from pdfem.case.shapes import RegionSection

START = "<!-- case-table:start -->"
END = "<!-- case-table:end -->"


def _section(annotation: Any) -> tuple[type[Section] | None, bool]:
    """The section class a field holds (or None for a value), and whether it is a list of them."""
    origin = typing.get_origin(annotation)
    if origin is tuple:
        args = [a for a in typing.get_args(annotation) if a is not Ellipsis]
        inner, _ = _section(args[0]) if len(args) == 1 else (None, False)
        return inner, inner is not None
    if origin in (typing.Union, types.UnionType):
        for arg in typing.get_args(annotation):
            inner, many = _section(arg)
            if inner is not None:
                return inner, many
        return None, False
    if isinstance(annotation, type) and issubclass(annotation, Section):
        return annotation, False
    return None, False


def split_description(text: str) -> tuple[str, str]:
    """``"Meaning (unit). Default: X."`` -> ``("Meaning (unit)", "X")``; ``"... Required."`` ->
    ``(..., "required")``."""
    text = " ".join(text.split())
    if text.endswith("Required."):
        return text[:-len("Required.")].strip().rstrip("."), "required"
    if " Required (" in text:  # "Required (note)."
        head, _, note = text.partition(" Required (")
        return head.rstrip("."), "required (" + note.rstrip(".")
    head, sep, default = text.rpartition("Default: ")
    if not sep:
        return text.rstrip("."), ""
    return head.strip().rstrip("."), default.strip().rstrip(".")


def _rows(cls: type[Section], prefix: str) -> Iterator[tuple[str, FieldInfo]]:
    for name, info in cls.model_fields.items():
        key = prefix + (info.alias or name)
        inner, many = _section(info.annotation)
        yield key, info
        if inner is not None and not issubclass(inner, RegionSection):
            yield from _rows(inner, key + ("[]." if many else "."))


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def markdown_table() -> str:
    """The README's case-file reference: one markdown table row per key of every section."""
    lines = ["| section | key | meaning (unit) | default |", "|---|---|---|---|"]
    for name, info in CaseFile.model_fields.items():
        cls, many = _section(info.annotation)
        label = f"`[[{name}]]`" if many else f"`[{name}]`"
        for key, field in _rows(cls, ""):
            meaning, default = split_description(field.description or "")
            lines.append(f"| {label} | `{key}` | {_cell(meaning)} | {_cell(default)} |")
            label = ""
    return "\n".join(lines) + "\n"


def replace_table(readme: str) -> str:
    """``readme`` with the text between the case-table markers replaced by :func:`markdown_table`."""
    head, start, rest = readme.partition(START)
    _, end, tail = rest.partition(END)
    if not (start and end):
        raise ValueError(f"the README has no {START} ... {END} markers")
    return head + START + "\n" + markdown_table() + END + tail
