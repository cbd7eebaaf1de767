"""A plot of a study: one output against one input, a line per value of the other inputs.

``pdfem sweep --collect DIR --plot OUTPUT:INPUT`` writes ``DIR/<OUTPUT>_vs_<INPUT>.png``
(matplotlib's Agg canvas, no screen): OUTPUT is a column of ``summary.csv``
(:mod:`pdfem.study.table`; its unit in brackets may be left out), INPUT one of the inputs
that vary. By default: the peak ice load on a structure (else the peak reaction of an ice
region; of several, the one with the largest peak over the runs; else the first output) against
the first input. Inputs that are not numbers are
placed one after the other in grid order, labelled by their values.
"""

from __future__ import annotations

import numbers
import re
from pathlib import Path
from typing import Any

from pdfem.errors import InputError
from pdfem.study.table import SweepTable
from pdfem.study.grid import value_label


def _bare(column: str) -> str:
    """A column name without its unit: ``loads.panel.peak [N]`` -> ``loads.panel.peak``."""
    return column.split(" [", 1)[0]


def _largest(table: SweepTable, column: str) -> float:
    """The largest value of a column over the runs (-inf if it has none)."""
    return max((float(r[column]) for r in table.rows if _number(r.get(column))),
               default=-float("inf"))


def choose(table: SweepTable, spec: str | None) -> tuple[str, str]:
    """The output and input columns of ``--plot OUTPUT:INPUT`` (or the defaults).

    Raises
    ------
    InputError
        (field ``--plot``) If the study has no input that varies or no output, or a name is
        not a column of the table.
    """
    outputs = [c for c in table.columns if c not in table.inputs and c not in ("run",
                                                                                "exit_status")]
    if not table.inputs or not outputs:
        raise InputError(str(table.path), "--plot", "nothing to plot: the study needs an "
                         "input that varies and runs with results")
    if spec is None:
        for kind in ("loads.", "regions."):
            peaks = [c for c in outputs if c.startswith(kind) and _bare(c).endswith(".peak")]
            if peaks:
                return max(peaks, key=lambda c: _largest(table, c)), table.inputs[0]
        return outputs[0], table.inputs[0]
    output, colon, input_ = spec.rpartition(":")
    found = [c for c in outputs if output in (c, _bare(c))]
    if not colon or not found or input_ not in table.inputs:
        raise InputError(str(table.path), "--plot", "give OUTPUT:INPUT, OUTPUT one of "
                         f"{', '.join(_bare(c) for c in outputs)} and INPUT one of "
                         f"{', '.join(table.inputs)}", spec)
    return found[0], input_


def _number(v: Any) -> bool:
    return isinstance(v, numbers.Real) and not isinstance(v, bool)


def write_plot(table: SweepTable, spec: str | None = None) -> Path:
    """Plot an output of ``table`` against an input (module docstring); the PNG's path.

    Raises
    ------
    InputError
        As :func:`choose`.
    """
    output, input_ = choose(table, spec)
    others = [k for k in table.inputs if k != input_]
    numeric = all(_number(r[input_]) for r in table.rows)
    order = {value_label(v): i for i, v in enumerate(dict.fromkeys(
        value_label(r[input_]) for r in table.rows))}
    lines: dict[str, list[tuple[float, float]]] = {}
    for r in table.rows:
        if not _number(r.get(output)):
            continue
        x = r[input_] if numeric else order[value_label(r[input_])]
        label = ", ".join(f"{k} = {value_label(r[k])}" for k in others)
        lines.setdefault(label, []).append((float(x), float(r[output])))
    from matplotlib.figure import Figure  # no pyplot: no global figure state, Agg canvas
    fig = Figure(figsize=(7.0, 4.5), layout="constrained")
    ax = fig.subplots()
    for label, points in lines.items():
        xs, ys = zip(*sorted(points))
        ax.plot(xs, ys, "o-", label=label or None)
    if not numeric:
        ax.set_xticks(list(order.values()), list(order))
    ax.set_xlabel(input_)
    ax.set_ylabel(output)
    ax.set_title(f"{_bare(output)} against {input_} ({len(table.rows)} runs)")
    ax.grid(alpha=0.3)
    if others:
        ax.legend(fontsize="small")
    name = re.sub(r"[^A-Za-z0-9._=-]", "_", f"{_bare(output)}_vs_{input_}") + ".png"
    path = table.path.parent / name
    fig.savefig(path, dpi=150, format="png")
    return path
