"""Running validation cases: each distinct run once, then every quantity measured from it.

Cases that share a run (same case file, ``execute`` and ``quick``) are grouped; each group's
case file is loaded (:func:`pdfem.validation.case.load_validation_case`), shrunk by ``quick``
when asked, run into its own directory, and measured. A run or a measurement that raises makes
its cases fail with the message; it never stops the other cases.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Callable

from pdfem.validation.case import CaseResult, Outcome, ValidationCase, load_validation_case
from pdfem.validation.report import save_plot


def _finite(x: float) -> float | None:
    return float(x) if x is not None and math.isfinite(x) else None


def _evaluate(case: ValidationCase, outcome: Outcome | None, failure: str, quick: bool,
              seconds: float, plot_dir: Path | None) -> CaseResult:
    """Measure one case from its run's outcome (or record the run's failure)."""
    res = CaseResult(case.name, case.quantity, case.unit, None, None, None, case.tolerance,
                     case.relative, False, case.source, case.case_file, quick, case.quick_note,
                     seconds, message=failure)
    if outcome is None:
        return res
    try:
        value = float(case.measure(outcome))
        reference = float(case.reference(outcome.case))
        error = case.error(value, reference)
    except Exception as exc:  # a measurement that cannot be made fails this case only
        res.message = f"measurement failed: {type(exc).__name__}: {exc}"
        return res
    res.value, res.reference, res.error = _finite(value), _finite(reference), _finite(error)
    res.passed = res.error is not None and res.error <= case.tolerance
    if not res.passed and res.error is None:
        res.message = "the measured value or its error is not finite"
    if plot_dir is not None and case.plot is not None:
        path = Path(plot_dir) / f"{case.name}.png"
        try:
            save_plot(case, outcome, value, reference, path)
            res.plot = path.name
        except Exception as exc:  # a figure that fails does not change the verdict
            res.message = (res.message + "; " if res.message else "") + \
                f"plot failed: {type(exc).__name__}: {exc}"
    return res


def run_validation(cases: tuple[ValidationCase, ...] | list[ValidationCase], work_dir: str | Path,
                   *, quick: bool = False, plot_dir: str | Path | None = None,
                   log: Callable[[str], None] | None = None) -> list[CaseResult]:
    """Run the validation cases and measure them.

    Parameters
    ----------
    cases
        The cases (e.g. :func:`pdfem.validation.registry.all_cases`).
    work_dir
        Directory for the runs (one subdirectory per run; created).
    quick
        Run each case's ``--quick`` variant.
    plot_dir
        Write a PNG per case here (``<name>.png``); ``None``: no plots.
    log
        Called with a line of progress per run (default: nothing).

    Returns
    -------
    list of CaseResult
        In the order of ``cases``.
    """
    say = log or (lambda s: None)
    groups: dict[tuple, list[ValidationCase]] = {}
    for c in cases:
        groups.setdefault(c.run_key(), []).append(c)
    results: dict[str, CaseResult] = {}
    for k, members in enumerate(groups.values()):
        first = members[0]
        directory = Path(work_dir) / f"{k:02d}_{Path(first.case_file).stem}"
        names = ", ".join(c.name for c in members)
        say(f"validate: running {first.case_file}{' (quick)' if quick else ''} for {names}")
        t0 = time.perf_counter()
        outcome, failure = None, ""
        try:
            case = load_validation_case(first.case_file)
            if quick:
                case = first.quick(case)
            directory.mkdir(parents=True, exist_ok=True)
            data = first.execute(case, directory)
            outcome = Outcome(case, data, directory, time.perf_counter() - t0)
        except Exception as exc:  # a run that fails fails its cases, not the whole validation
            failure = f"run failed: {type(exc).__name__}: {exc}"
        seconds = time.perf_counter() - t0
        for c in members:
            results[c.name] = r = _evaluate(c, outcome, failure, quick, seconds, plot_dir)
            verdict = "pass" if r.passed else "FAIL"
            say(f"validate:   {c.name}: {verdict}" + (f" ({r.message})" if r.message else ""))
        say(f"validate:   {seconds:.1f} s")
    return [results[c.name] for c in cases]
