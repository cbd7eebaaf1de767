"""``pdfem schema [--markdown]``: the JSON Schema of a case file (or its markdown reference).

Editors that read JSON Schema check and complete case files with it, e.g. taplo / Even Better
TOML with ``#:schema ./pdfem-case.schema.json`` as the first line of the case after
``pdfem schema > pdfem-case.schema.json``.
"""

from __future__ import annotations

import argparse
import json

from pdfem.errors import EXIT_OK

NAME = "schema"
HELP = "JSON Schema of the case file (for TOML editors)"


def add_arguments(s: argparse.ArgumentParser) -> None:
    """The options of ``pdfem schema``."""
    s.add_argument("--markdown", action="store_true",
                   help="print the case-file reference table (the README's) instead")


def run(args: argparse.Namespace) -> int:
    """Print the schema; exit status."""
    from pdfem.case.doc import markdown_table
    from pdfem.case.schema import json_schema

    if args.markdown:
        print(markdown_table(), end="")
    else:
        print(json.dumps(json_schema(), indent=2))
    return EXIT_OK
