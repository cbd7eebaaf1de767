"""Preparing a parameter study: every case of the grid validated, then its folder written.

:func:`plan_sweep` makes the case of each run of a grid (:mod:`pdfem.study.grid`) from the base
case with :func:`pdfem.case.overrides.override_case`, so every run is checked by the schema
before anything runs or is written; a value the schema refuses is an
:class:`~pdfem.errors.InputError` naming its ``--set`` key. Then it writes the study folder
(:mod:`pdfem.study.folder`): ``sweep.json`` and each run's ``case.toml``.

A folder takes up a study again: the same base case and keys, and runs whose case files are
unchanged. New values of the same keys add runs; a changed base case or another set of keys
is refused (a run's ``case.toml`` that differs would mix the results of two studies).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

from pdfem.case.config import Case
from pdfem.case.overrides import key_parts, override_case
from pdfem.case.toml_text import value_text
from pdfem.errors import InputError
from pdfem.run.outdir import check_out_dir
from pdfem.study.folder import SweepFolder
from pdfem.study.grid import GridRun, grid_runs, parse_value


@dataclass(frozen=True)
class PlannedRun:
    """A run of a study: its name (folder), its values and its validated case."""

    name: str
    values: dict[str, Any]
    case: Case


def _blamed_key(field: str | None, keys: Sequence[str]) -> str | None:
    """The key whose path leads to (or lies below) the schema's ``field``, if one does."""
    if not field:
        return None
    path = key_parts(field)
    for key in keys:
        parts = key_parts(key)
        n = min(len(parts), len(path))
        if parts[:n] == path[:n]:
            return key
    return None


def _run_case(base: Case, run: GridRun) -> Case:
    """The case of one run, with a refused value named by its ``--set`` key."""
    try:
        return override_case(base, run.values)
    except InputError as exc:
        key = _blamed_key(exc.field, list(run.values))
        where = f"--set {key}" if key else "--set"
        field = f", field {exc.field}" if exc.field and exc.field != key else ""
        raise InputError(exc.file, where, f"{exc.message} (run {run.name}{field})",
                         exc.value) from None


def _plain_values(key: str, values: Any) -> Any:
    """A key's values as plain TOML values (numpy numbers and arrays of values become floats
    and lists); anything but a list of values is left for :func:`grid_runs` to refuse."""
    if isinstance(values, (str, bytes, Mapping)) or not isinstance(values, Iterable):
        return values
    try:
        return [parse_value(value_text(v)) for v in values]
    except TypeError as exc:
        raise InputError(None, f"--set {key}", f"not a value a case file can hold ({exc})") \
            from None


def _manifest(folder: SweepFolder, base: Case, keys: list[str], runs: list[GridRun]) -> dict:
    """The study's description, this grid's runs added to those the folder has."""
    case = str(Path(base.file).resolve())
    old = folder.read_manifest()
    if old is None:
        return {"case": case, "keys": keys, "runs": [{"name": r.name, "values": r.values}
                                                    for r in runs]}
    if old.get("case") != case or old["keys"] != keys:
        raise InputError(None, "--out", f"{folder.root} holds a sweep of {old.get('case')} over "
                         f"{', '.join(old['keys'])}; give another --out for a sweep of {case} "
                         f"over {', '.join(keys)}", str(folder.root))
    names = {r["name"] for r in old["runs"]}
    old["runs"] += [{"name": r.name, "values": r.values} for r in runs if r.name not in names]
    return old


def plan_sweep(base: Case, grid: Mapping[str, Sequence[Any]], out: str | Path) -> \
        tuple[SweepFolder, list[PlannedRun]]:
    """Validate every run of ``grid`` over ``base`` and write the study folder ``out``.

    Parameters
    ----------
    base
        The validated base case (:func:`pdfem.case.load_case`).
    grid
        ``{dotted key: values}`` (:func:`pdfem.study.grid.grid_runs`).
    out
        The study folder (created).

    Returns
    -------
    folder : SweepFolder
    runs : list of PlannedRun
        This grid's runs in grid order.

    Raises
    ------
    InputError
        A bad key or value (naming its ``--set`` key), an ``out`` that cannot be written, or a
        folder that holds another study (module docstring). Nothing is written then.
    """
    grid = {k: _plain_values(k, vs) for k, vs in grid.items()}
    runs = grid_runs(grid)
    planned = [PlannedRun(r.name, r.values, _run_case(base, r)) for r in runs]
    folder = SweepFolder(Path(out))
    manifest = _manifest(folder, base, list(grid), runs) if folder.root.is_dir() else None
    for p in planned:
        path = folder.case_file(p.name)
        if path.is_file() and path.read_text() != p.case.text:
            raise InputError(str(path), None, "this run's case file differs from the one this "
                             "sweep would write (the base case changed since it ran); give "
                             "another --out, or remove the run's folder to run it again")
    check_out_dir(folder.root)
    folder.write_manifest(manifest or _manifest(folder, base, list(grid), runs))
    for p in planned:
        path = folder.case_file(p.name)
        if not path.is_file():
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(p.case.text)
    return folder, planned
