"""Validation of pdfem against analytic references: ``pdfem validate``.

- :mod:`pdfem.validation.case` -- the :class:`ValidationCase` record (case file, quantity,
  measurement, cited reference, tolerance, ``--quick`` variant);
- :mod:`pdfem.validation.cases` -- one module per case file of ``models/validation/``;
- :mod:`pdfem.validation.registry` -- the list of case modules (one line each);
- :mod:`pdfem.validation.measure` -- shared signal measurements;
- :mod:`pdfem.validation.runner` -- runs each distinct run once and measures its cases;
- :mod:`pdfem.validation.report` -- the table, the JSON object, the markdown report and plots.
"""

from pdfem.validation.case import Outcome, ValidationCase
from pdfem.validation.registry import all_cases
from pdfem.validation.case import CaseResult
from pdfem.validation.runner import run_validation

__all__ = ["CaseResult", "Outcome", "ValidationCase", "all_cases", "run_validation"]
