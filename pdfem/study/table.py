"""The table of a study: one row per run, the inputs that vary and the key outputs.

:func:`collect` reads each run's results with the summary of ``pdfem post``
(:func:`pdfem.post.summarize`) and writes ``DIR/summary.csv``. Its columns:

- ``run``: the run's name (its folder ``runs/<name>``);
- the inputs that vary: each key of the study that takes more than one value;
- the key outputs (SI units, in the column name), each a figure of the post summary:
  per structure ``loads.<structure>.peak``, ``.mean`` and ``.per_step_peak`` (the magnitude of
  the ice force: its largest 0.1 ms average, the headline figure that converges with the step;
  its time average; and its largest per-step sample, step-dependent; N, docs/post.md);
  per fixed or prescribed ice region the same figures of its reaction, ``regions.<body>.<region>.*``;
  per ship hull its ice resistance ``resistance.<hull>.mean`` and ``.peak`` (N); per rotating
  structure ``shaft.<name>.peak_ice_torque``, ``.mean_ice_torque`` (N m) and ``.mean_thrust``
  (N); per elastic structure the peak von Mises stress ``structures.<name>.max_von_mises``
  (Pa) and where, ``.max_von_mises_x``, ``_y``, ``_z`` (m); the energy ``energy.residual`` and
  ``energy.supplied`` (J, last frame);
- ``exit_status``: of ``pdfem run`` (0 done, 3 stopped by a blow-up, 1 or 2 failed), empty for
  a run that has not ended (its outputs, if any, are those of the frames written so far).

A figure a run does not have (no such structure, no results yet) is an empty cell.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pdfem.errors import InputError
from pdfem.post import load_results, summarize
from pdfem.study.folder import SweepFolder

SUMMARY = "summary.csv"
"""The table's name in the study folder."""

_LOAD_FIGURES = ((("magnitude", "peak"), "peak"), (("magnitude", "mean"), "mean"),
                 (("magnitude", "per_step_peak"), "per_step_peak"))
OUTPUTS: tuple[tuple[str, tuple[tuple[tuple[str, ...], str], ...], str], ...] = (
    ("loads", _LOAD_FIGURES, "N"),
    ("regions", _LOAD_FIGURES, "N"),
    ("resistance", ((("mean",), "mean"), (("peak",), "peak")), "N"),
    ("shaft", ((("peak_ice_torque", "value"), "peak_ice_torque"),
               (("mean_ice_torque",), "mean_ice_torque")), "N m"),
    ("shaft", ((("mean_thrust",), "mean_thrust"),), "N"),
    ("structures", ((("max_von_mises", "value"), "max_von_mises"),), "Pa"),
    ("structures", ((("max_von_mises", "location"), "max_von_mises"),), "m"),
)
"""The key outputs: per summary section, ``(path of the figure in a part, column name,
unit)``; a location (a list of 3) is three columns ``_x``, ``_y``, ``_z``."""


@dataclass(frozen=True)
class SweepTable:
    """The table of a study: column names (with units) and one dict per run."""

    columns: list[str]
    rows: list[dict[str, Any]]
    path: Path
    """The CSV file written."""
    inputs: list[str]
    """The columns of the inputs that vary."""
    plot: Path | None = None
    """The plot written with the table, if any (:mod:`pdfem.study.plot`)."""


def _figure(part: dict, path: tuple[str, ...]) -> Any:
    for p in path:
        if not isinstance(part, dict) or p not in part:
            return None
        part = part[p]
    return part


def key_outputs(summary: dict) -> dict[str, float | None]:
    """The key outputs of one run's post summary (module docstring), by column name."""
    out: dict[str, float | None] = {}
    for section, figures, unit in OUTPUTS:
        for name, part in summary.get(section, {}).items():
            for path, column in figures:
                value = _figure(part, path)
                if isinstance(value, list):
                    for axis, v in zip("xyz", value):
                        out[f"{section}.{name}.{column}_{axis} [{unit}]"] = v
                elif path[0] in part:
                    out[f"{section}.{name}.{column} [{unit}]"] = value
    for key in ("residual", "supplied"):
        if key in summary.get("energy", {}):
            out[f"energy.{key} [J]"] = summary["energy"][key]
    return out


def _run_outputs(folder: SweepFolder, name: str) -> dict[str, float | None]:
    """The key outputs of run ``name``; none if it has no readable results yet."""
    try:
        return key_outputs(summarize(load_results(folder.results(name))))
    except InputError:
        return {}


def _cell(v: Any) -> Any:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "" if v is None else repr(v)
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, (list, tuple)):
        return ",".join(str(_cell(x)) for x in v)
    return v


def collect(out: str | Path) -> SweepTable:
    """Write ``summary.csv`` of the study in ``out`` (module docstring).

    Parameters
    ----------
    out
        The study folder (``pdfem sweep ... --out DIR``).

    Returns
    -------
    SweepTable
        The table written, one row per run of the study in grid order.

    Raises
    ------
    InputError
        If ``out`` holds no study (no ``sweep.json``).
    """
    folder = SweepFolder(Path(out))
    manifest = folder.read_manifest()
    if manifest is None:
        raise InputError(str(out), "--collect", "no sweep here (no sweep.json); give the --out "
                         "folder of a pdfem sweep")
    runs = manifest["runs"]
    inputs = [k for k in manifest["keys"]
              if len({repr(r["values"].get(k)) for r in runs}) > 1]
    rows, outputs = [], {}
    for r in runs:
        values = _run_outputs(folder, r["name"])
        outputs.update(dict.fromkeys(values))
        rows.append({"run": r["name"], **{k: r["values"].get(k) for k in inputs}, **values,
                     "exit_status": folder.status(r["name"])})
    columns = ["run", *inputs, *outputs, "exit_status"]
    path = folder.root / SUMMARY
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(columns)
        for row in rows:
            writer.writerow([_cell(row.get(c)) for c in columns])
    return SweepTable(columns, rows, path, inputs)
