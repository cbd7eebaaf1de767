"""Errors that the command line turns into exit statuses and one-paragraph messages.

``InputError`` (exit 2) is for anything the user gave us that is wrong: it names the file,
the field, the value and what would be valid. ``InstabilityError`` (exit 3) stops a run whose
state blew up. ``OutputError`` (exit 1, no traceback) is a results or checkpoint file that
could not be written (no space left, a file-size limit, an I/O error). Every other exception
is a bug or an environment failure (exit 1). A run stopped by a signal (SIGTERM, SIGUSR1,
SIGINT) with a checkpoint to restart from is not an error: exit 4 (:data:`EXIT_STOPPED`).
"""

from __future__ import annotations

import reprlib
from typing import Any

EXIT_OK = 0
EXIT_FAILURE = 1
EXIT_BAD_INPUT = 2
EXIT_INSTABILITY = 3
EXIT_STOPPED = 4
"""A run stopped by a signal after writing a checkpoint and a last frame (:mod:`pdfem.run.stop`)."""


SHOWN_CHARS = 200
"""Longest shown value in a message; a longer one (a mistyped table or a nested array pasted
into a field) is cut in the middle."""


def shown(value: Any) -> str:
    """``repr(value)`` for a message, at most about :data:`SHOWN_CHARS` characters."""
    try:
        text = repr(value)
    except RecursionError:  # nested deeper than repr goes
        text = reprlib.repr(value)
    if len(text) <= SHOWN_CHARS:
        return text
    return text[:SHOWN_CHARS - 40] + " ... " + text[-30:]


class InputError(Exception):
    """Bad user input: a case file, a mesh or a parameter.

    Parameters
    ----------
    file
        The file the input came from (``None`` for command-line values).
    field
        Dotted path of the offending field, e.g. ``ice[0].material.poisson_ratio``.
    message
        What is wrong and what would be valid, as a sentence.
    value
        The offending value (shown with ``repr``), if any.
    """

    def __init__(self, file: str | None, field: str | None, message: str, value: Any = ...):
        self.file = file
        self.field = field
        self.value = value
        self.message = message
        super().__init__(self.text())

    def text(self) -> str:
        """The one-paragraph message shown to the user."""
        where = []
        if self.file:
            where.append(f"in {self.file}")
        if self.field:
            where.append(f"field '{self.field}'")
        head = ("Error " + ", ".join(where) + ": ") if where else "Error: "
        val = "" if self.value is ... else f" (got {shown(self.value)})"
        return head + self.message.rstrip(".") + val + "."


class InstabilityError(Exception):
    """A run stopped because its state became unphysical (NaN, runaway motion, energy growth)."""


class OutputError(Exception):
    """A results or checkpoint file could not be written: the message (one paragraph) says
    what failed, where, how much was written and what is kept."""
