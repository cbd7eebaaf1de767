"""Reports of a validation: the terminal table, the JSON object, the markdown file and its plots.

Figures use matplotlib's object API (:class:`matplotlib.figure.Figure`, no pyplot: no global
state, no screen needed); each case draws its own evidence on the figure it is given.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the runner imports this module; only types come back
    from pdfem.validation.case import CaseResult, Outcome, ValidationCase

COLUMNS = ("case", "quantity", "pdfem", "reference", "unit", "error", "tolerance", "pass")


def save_plot(case: "ValidationCase", outcome: "Outcome", value: float, reference: float,
              path: Path) -> Path:
    """Draw ``case``'s plot of ``outcome`` and write it as a PNG to ``path``."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    case.plot(fig, outcome, value, reference)
    fig.suptitle(f"{case.name}: {case.quantity}", fontsize="medium")
    fig.savefig(path, dpi=110, format="png")
    return path


def _number(x: float | None) -> str:
    return "-" if x is None else f"{x:.6g}"


def _error(r: "CaseResult", x: float | None) -> str:
    if x is None:
        return "-"
    return f"{100 * x:.3g} %" if r.relative else f"{x:.3g}"


def rows(results: list["CaseResult"]) -> list[tuple[str, ...]]:
    """The table's rows (strings), one per result, in the order of :data:`COLUMNS`."""
    return [(r.name, r.quantity, _number(r.value), _number(r.reference), r.unit, _error(r, r.error),
             _error(r, r.tolerance), "yes" if r.passed else "NO") for r in results]


def format_table(results: list["CaseResult"], quick: bool) -> str:
    """The plain-text table of the results with a closing verdict line."""
    table = [COLUMNS, *rows(results)]
    widths = [max(len(row[k]) for row in table) for k in range(len(COLUMNS))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in table]
    lines.insert(1, "  ".join("-" * w for w in widths))
    for r in results:
        if r.message:
            lines.append(f"{r.name}: {r.message}")
    failed = [r.name for r in results if not r.passed]
    mode = "quick " if quick else ""
    lines.append(f"{len(results) - len(failed)} of {len(results)} {mode}validation cases pass"
                 + (f"; failed: {', '.join(failed)}" if failed else ""))
    return "\n".join(lines)


def as_json(results: list["CaseResult"], quick: bool, seconds: float) -> dict:
    """The results as one JSON-serialisable object (``passed`` is the overall verdict)."""
    return {"quick": quick, "passed": all(r.passed for r in results), "cases": len(results),
            "failed": [r.name for r in results if not r.passed], "seconds": seconds,
            "results": [r.as_dict() for r in results]}


def write_markdown(results: list["CaseResult"], directory: str | Path, quick: bool,
                   seconds: float) -> Path:
    """Write ``directory/validation.md``: the table, then per case its reference and plot."""
    directory = Path(directory)
    failed = [r for r in results if not r.passed]
    lines = [f"# pdfem validation{' (quick)' if quick else ''}", "",
             f"{len(results) - len(failed)} of {len(results)} cases pass "
             f"({seconds:.0f} s wall time). Produced by `pdfem validate"
             f"{' --quick' if quick else ''} --report`; the case files are in "
             "`models/validation/`. Errors are relative (%), absolute where the reference is 0.", "",
             "| " + " | ".join(COLUMNS) + " |", "|" + "---|" * len(COLUMNS)]
    lines += ["| " + " | ".join(row) + " |" for row in rows(results)]
    for r in results:
        lines += ["", f"## {r.name}: {r.quantity}", "",
                  f"- case file: `models/validation/{r.case_file}`"
                  + (f" (quick: {r.quick_note})" if r.quick else ""),
                  f"- reference: {r.source}",
                  f"- pdfem {_number(r.value)} {r.unit}, reference {_number(r.reference)} {r.unit}, "
                  f"error {_error(r, r.error)} (tolerance {_error(r, r.tolerance)}): "
                  f"**{'pass' if r.passed else 'FAIL'}**; run {r.seconds:.1f} s"]
        if r.message:
            lines.append(f"- note: {r.message}")
        if r.plot:
            lines += ["", f"![{r.name}]({r.plot})"]
    path = directory / "validation.md"
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
