"""Option types shared by the commands' argument parsers."""

from __future__ import annotations

import argparse


def path_text(value: str) -> str:
    """An option naming a file or directory: any non-empty text (an empty one would mean the
    current directory, or, for an optional output, nothing at all, and be ignored).

    Raises
    ------
    argparse.ArgumentTypeError
        For an empty or blank value (the parser reports it as bad input, exit 2).
    """
    if not value.strip():
        raise argparse.ArgumentTypeError("give a file or directory name, not an empty string")
    return value
