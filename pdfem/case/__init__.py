"""The case file: its schema and loading (TOML -> a validated :class:`~pdfem.case.schema.Case`)."""

from pdfem.case.schema import Case, load_case, parse_case

__all__ = ["Case", "load_case", "parse_case"]
