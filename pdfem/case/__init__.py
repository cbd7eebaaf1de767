"""The case file: its schema and loading (TOML -> a validated :class:`~pdfem.case.schema.Case`)."""
