"""Run every case file shortened and compare two such sets of results array by array.

A change that should not alter any answer (a refactoring) is checked by running the case files
of ``models/`` and ``models/validation/`` with the old and the new code and comparing every
array of every results file: ``run`` writes ``OUT/<stem>/results.h5`` for each case, shortened
to two frames of at most 1 ms (the first milliseconds of each, as the tests' model runs do);
``diff`` walks two such trees and reports, per case, whether every array is bit-identical and
otherwise the largest difference relative to each array's largest magnitude.

    python -m pdfem.benchmarks.compare_runs run OUT [--cases a b ...]
    mpiexec -n 2 python -m pdfem.benchmarks.compare_runs run OUT2
    python -m pdfem.benchmarks.compare_runs diff OLD NEW [--json]

The runner uses only :func:`pdfem.case.schema.load_case` and :func:`pdfem.run.driver.run_case`,
so the file can be run with an older checkout's interpreter (``OLD_VENV/bin/python
benchmarks/compare_runs.py run OUT``, from outside the new tree) to produce the reference.
Units: whatever each array holds (SI); differences are relative, dimensionless.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

import h5py
import numpy as np


def case_files(root: Path | None = None) -> list[Path]:
    """The case files of ``models/`` and ``models/validation/`` (sorted)."""
    if root is None:
        import pdfem.models

        root = Path(list(pdfem.models.__path__)[0])
    return sorted(root.glob("*.toml")) + sorted((root / "validation").glob("*.toml"))


def shorten(case, frame_cap: float = 1.0e-3):
    """``case`` ending after two frames of at most ``frame_cap`` seconds each."""
    frame = min(case.run.output_interval, frame_cap)
    return dataclasses.replace(case, run=dataclasses.replace(
        case.run, end_time=2 * frame, output_interval=frame))


def run_all(out: Path, names: list[str] | None = None, frame_cap: float = 1.0e-3) -> None:
    """Run every case (or those whose stem is in ``names``) shortened to two frames of at
    most ``frame_cap`` (s) into ``out/<key>``; ``key`` is the stem, prefixed ``validation.``
    for the validation cases."""
    from pdfem.case.schema import load_case
    from pdfem.run.driver import run_case

    for path in case_files():
        key = ("validation." if path.parent.name == "validation" else "") + path.stem
        if names and key not in names and path.stem not in names:
            continue
        run_case(shorten(load_case(path), frame_cap), out / key, quiet=True)


def _arrays(path: Path) -> dict[str, np.ndarray]:
    """Every dataset of an HDF5 file by its path."""
    out = {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                out[name] = obj[()]
        f.visititems(visit)
    return out


def _relative(x: np.ndarray, y: np.ndarray) -> float:
    """Largest |y - x| over the largest |x| (0: bit-identical; inf: shapes or kinds differ)."""
    if x.shape != y.shape:
        return np.inf
    if np.array_equal(x, y, equal_nan=x.dtype.kind in "fc"):
        return 0.0
    if x.dtype.kind not in "fc":
        return np.inf
    scale = float(np.abs(x[np.isfinite(x)]).max(initial=0.0)) or 1.0
    return float(np.abs(np.nan_to_num(y - x, nan=np.inf)).max()) / scale


def compare(old: Path, new: Path) -> dict:
    """Per case of ``old``: ``{"identical": bool, "arrays": n, "differ": {path: rel}}``, with
    ``rel`` the largest |new - old| over the array's largest |old| (inf: missing, shapes or
    kinds differ); cases missing from ``new`` are reported as such."""
    report = {}
    for d in sorted(p for p in old.iterdir() if (p / "results.h5").is_file()):
        other = new / d.name / "results.h5"
        if not other.is_file():
            report[d.name] = {"identical": False, "missing": True}
            continue
        a, b = _arrays(d / "results.h5"), _arrays(other)
        differ = {}
        for key in sorted(set(a) | set(b)):
            rel = np.inf if key not in a or key not in b else _relative(a[key], b[key])
            if rel != 0.0:
                differ[key] = rel
        report[d.name] = {"identical": not differ, "arrays": len(a), "differ": differ}
    return report


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("run")
    r.add_argument("out", type=Path)
    r.add_argument("--cases", nargs="*")
    r.add_argument("--frame", type=float, default=1.0e-3,
                   help="longest frame (s); the runs end after two frames")
    d = sub.add_parser("diff")
    d.add_argument("old", type=Path)
    d.add_argument("new", type=Path)
    d.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    if args.cmd == "run":
        run_all(args.out, args.cases, args.frame)
        return 0
    report = compare(args.old, args.new)
    if args.json:
        print(json.dumps(report, indent=1))
    else:
        for name, r in report.items():
            if r.get("missing"):
                print(f"{name:45s} MISSING")
            elif r["identical"]:
                print(f"{name:45s} identical ({r['arrays']} arrays)")
            else:
                print(f"{name:45s} {len(r['differ'])} of {r['arrays']} arrays differ:")
                for key, rel in r["differ"].items():
                    print(f"    {key:60s} {rel:.3e}")
    return 0 if all(r.get("identical") for r in report.values()) else 1


if __name__ == "__main__":
    sys.exit(main())
