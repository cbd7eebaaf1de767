"""The validation case record: one checked quantity of one run, with its cited reference.

A :class:`ValidationCase` names a case file of ``models/validation/`` (package data of
``pdfem.models``), how to run it (:func:`run_and_read` by default: :func:`pdfem.run.driver.run_case`
and :func:`pdfem.output.read_results`), how ``--quick`` shrinks it, a function that measures one
quantity from what the run left (an :class:`Outcome`), the reference value of that quantity for
the case as run, and where the reference comes from. Several cases may measure the same run
(same case file, same ``execute`` and ``quick`` functions): the runner runs it once.
"""

from __future__ import annotations

import dataclasses
import importlib.resources
from contextlib import AbstractContextManager
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Callable

from pdfem.case import Case, load_case
from pdfem.output import read_results
from pdfem.run.driver import run_case


@dataclass
class Outcome:
    """What a run (or a direct computation) of a validation case file left behind.

    Attributes
    ----------
    case
        The case as it was run (after the ``--quick`` change).
    data
        What ``execute`` returned: for :func:`run_and_read` the :func:`pdfem.output.read_results`
        dictionary of the run; other executors document their own.
    directory
        The directory the run wrote into.
    seconds
        Wall time of the run, s.
    """

    case: Case
    data: dict[str, Any]
    directory: Path
    seconds: float


def run_and_read(case: Case, directory: Path) -> dict[str, Any]:
    """Run ``case`` into ``directory`` (quietly) and read its ``results.h5`` back."""
    return read_results(run_case(case, directory, quiet=True).results)


def unchanged(case: Case) -> Case:
    """The ``--quick`` variant of a case that is already small: the case itself."""
    return case


@dataclass(frozen=True)
class ValidationCase:
    """One quantity of one validation run against its reference.

    Attributes
    ----------
    name
        Short unique identifier (``wave_speed``), used on the command line and in reports.
    case_file
        File name of the case in ``models/validation/`` (package ``pdfem.models``).
    quantity
        What is measured, in words (``bar wave speed``).
    unit
        SI unit of the quantity (``m/s``; ``-`` for a ratio).
    measure
        ``measure(outcome) -> float``: the quantity from the run's results.
    reference
        ``reference(case) -> float``: the reference value for the case as run (from its own
        parameters, so that the ``--quick`` variant is checked against its own reference).
    source
        Where the reference comes from: the formula and a citation.
    tolerance
        Largest accepted error: relative ``|value - reference| / |reference|`` or, with
        ``relative = False``, absolute ``|value - reference|`` (in ``unit``).
    quick_note
        How ``--quick`` shrinks the run, in words.
    quick
        ``quick(case) -> case``: the ``--quick`` variant (coarser, shorter, but still a real check).
    execute
        ``execute(case, directory) -> dict``: runs the case; default :func:`run_and_read`.
    relative
        Whether ``tolerance`` is relative (default) or absolute.
    plot
        ``plot(figure, outcome, value, reference)``: draws the evidence on a matplotlib
        :class:`~matplotlib.figure.Figure` for the report (optional).
    """

    name: str
    case_file: str
    quantity: str
    unit: str
    measure: Callable[[Outcome], float]
    reference: Callable[[Case], float]
    source: str
    tolerance: float
    quick_note: str
    quick: Callable[[Case], Case] = unchanged
    execute: Callable[[Case, Path], dict] = run_and_read
    relative: bool = True
    plot: Callable[..., None] | None = None

    def run_key(self) -> tuple:
        """Cases with equal keys measure the same run."""
        return (self.case_file, self.execute, self.quick)

    def error(self, value: float, reference: float) -> float:
        """The error of ``value`` against ``reference`` as the tolerance measures it."""
        if self.relative:
            return abs(value - reference) / abs(reference)
        return abs(value - reference)


def case_path(case_file: str) -> AbstractContextManager[Path]:
    """The installed case file ``models/validation/<case_file>`` as a context manager of a path."""
    return importlib.resources.as_file(importlib.resources.files("pdfem.models") / "validation" / case_file)


def load_validation_case(case_file: str) -> Case:
    """Load and validate ``models/validation/<case_file>`` (:func:`pdfem.case.load_case`)."""
    with case_path(case_file) as path:
        return load_case(path)


def _noted(case: Case, section: str, changes: dict) -> str:
    """The case text with a closing comment recording ``changes`` (the results file stores the
    case text, so a changed run says how it differs from its file)."""
    lines = "".join(f"\n# changed for this run: {section}.{k} = {v!r}" for k, v in changes.items())
    return case.text.rstrip("\n") + "\n" + lines + "\n"


def replace_run(case: Case, **changes) -> Case:
    """``case`` with fields of its ``[run]`` section replaced (e.g. ``end_time``)."""
    return dataclasses.replace(case, run=dataclasses.replace(case.run, **changes),
                               text=_noted(case, "run", changes))


def replace_ice(case: Case, index: int = 0, **changes) -> Case:
    """``case`` with fields of its ``index``-th ``[[ice]]`` body replaced (e.g. ``shape``)."""
    ice = list(case.ice)
    ice[index] = dataclasses.replace(ice[index], **changes)
    return dataclasses.replace(case, ice=tuple(ice), text=_noted(case, f"ice[{index}]", changes))


def replace_structure(case: Case, index: int = 0, **changes) -> Case:
    """``case`` with fields of its ``index``-th ``[[structure]]`` replaced (e.g. ``params``)."""
    st = list(case.structures)
    st[index] = dataclasses.replace(st[index], **changes)
    return dataclasses.replace(case, structures=tuple(st),
                               text=_noted(case, f"structure[{index}]", changes))


@dataclass
class CaseResult:
    """The figures of one validation case (SI units; ``None`` where the run or measurement failed).

    ``error`` is relative (``|value - reference| / |reference|``) when ``relative``, else
    absolute (in ``unit``); the case passes when it is at most ``tolerance``. ``seconds`` is the
    wall time of the run the case measured (shared by the cases of one run); ``plot`` the PNG
    file name in the report directory, if one was written; ``message`` says what went wrong.
    """

    name: str
    quantity: str
    unit: str
    value: float | None
    reference: float | None
    error: float | None
    tolerance: float
    relative: bool
    passed: bool
    source: str
    case_file: str
    quick: bool
    quick_note: str
    seconds: float
    plot: str | None = None
    message: str = ""

    def as_dict(self) -> dict:
        """The result as JSON-serialisable values."""
        return asdict(self)
