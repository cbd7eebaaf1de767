"""Compare two results files array by array (a refactoring must not change any result).

    python benchmarks/compare_results.py OLD_DIR NEW_DIR [--tol 0]

OLD_DIR and NEW_DIR are output directories of ``pdfem run`` (or ``results.h5`` files). Every
dataset under ``/`` is compared (``/meta``'s attributes hold a time stamp and are skipped, its
datasets are compared); per-rank files ``results.rank<R>.h5`` beside ``results.h5`` are compared
too. Prints one line per differing or missing array and exits 1 if any differs by more than
``--tol`` (absolute; 0 = bit for bit), 0 otherwise.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import h5py
import numpy as np


def _datasets(f: h5py.File) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    f.visititems(lambda name, obj: out.__setitem__(name, obj[()])
                 if isinstance(obj, h5py.Dataset) else None)
    return out


def compare_files(old: Path, new: Path, tol: float = 0.0) -> list[str]:
    """Lines describing every array of ``old`` and ``new`` that differs by more than ``tol``."""
    with h5py.File(old, "r") as a, h5py.File(new, "r") as b:
        da, db = _datasets(a), _datasets(b)
    lines = [f"{name}: only in {old}" for name in sorted(da.keys() - db.keys())]
    lines += [f"{name}: only in {new}" for name in sorted(db.keys() - da.keys())]
    for name in sorted(da.keys() & db.keys()):
        x, y = da[name], db[name]
        if x.shape != y.shape:
            lines.append(f"{name}: shape {x.shape} != {y.shape}")
        elif x.dtype.kind in "fc":
            d = float(np.max(np.abs(x - y), initial=0.0)) if x.size else 0.0
            same_nan = np.array_equal(np.isnan(x), np.isnan(y))
            if d > tol or not same_nan:
                lines.append(f"{name}: max |difference| {d:.3e}")
        elif not np.array_equal(x, y):
            lines.append(f"{name}: differs")
    return lines


def _files(path: Path) -> list[Path]:
    if path.is_file():
        return [path]
    return sorted(path.glob("results*.h5"))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("old", type=Path)
    p.add_argument("new", type=Path)
    p.add_argument("--tol", type=float, default=0.0, help="absolute tolerance (0: bit for bit)")
    a = p.parse_args(argv)
    old, new = _files(a.old), _files(a.new)
    if [f.name for f in old] != [f.name for f in new] or not old:
        print(f"different result files: {[f.name for f in old]} vs {[f.name for f in new]}")
        return 1
    bad = 0
    for fo, fn in zip(old, new):
        lines = compare_files(fo, fn, a.tol)
        bad += len(lines)
        print(f"{fn}: {'identical' if not lines else f'{len(lines)} arrays differ'}")
        for line in lines:
            print("  " + line)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
