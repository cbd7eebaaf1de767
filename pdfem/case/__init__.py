"""The case file: its schema (pydantic models, :mod:`pdfem.case.schema`) and loading
(TOML -> a validated :class:`~pdfem.case.config.Case`, :mod:`pdfem.case.loader`)."""

from pdfem.case.schema import Case, json_schema, load_case, parse_case

__all__ = ["Case", "json_schema", "load_case", "parse_case"]
