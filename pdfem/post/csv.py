"""The per-step histories of a results file (loads, contact pairs, monitors, shaft loads, ship
motions) as one CSV table.

:func:`history_table` puts the histories side by side on the union of their step times;
:func:`write_csv` writes that table with a header of column names and units.
"""

from __future__ import annotations

import os

import numpy as np

from pdfem.output.source import UNITS
from pdfem.post.groups import AXES

LOAD_PREFIXES = ("loads/", "contacts/", "monitors/", "shaft/", "motions/")
"""History groups written at every coupling step (the CSV columns)."""


def _columns_of(group: str, key: str, a: np.ndarray) -> list[tuple[str, np.ndarray]]:
    unit = UNITS.get(key)
    suffix = f" [{unit}]" if unit else ""
    if a.ndim == 1:
        return [(f"{group}/{key}{suffix}", a)]
    flat = a.reshape(a.shape[0], -1)
    names = {3: AXES, 6: ("xx", "yy", "zz", "yz", "xz", "xy")}.get(
        flat.shape[1], tuple(str(i) for i in range(flat.shape[1])))
    return [(f"{group}/{key}_{c}{suffix}", flat[:, i]) for i, c in enumerate(names)]


def history_table(results: dict) -> tuple[list[str], np.ndarray]:
    """The per-step histories (loads, contact pairs, monitors) as one table.

    Parameters
    ----------
    results
        :func:`pdfem.post.load.load_results` of a file.

    Returns
    -------
    names : list of str
        ``"time [s]"`` then one name per column, ``<group>/<key>[_x|_y|_z] [<unit>]``, e.g.
        ``loads/panel/force_x [N]``; groups in the order loads, contacts, monitors, shaft
        loads (:mod:`pdfem.motion.shaft_loads`), ship motions.
    table : numpy.ndarray
        (K, len(names)) values; rows are the union of the groups' step times (the same
        steps in a file from :func:`pdfem.run.driver.run_case`), NaN where a group has no row.
    """
    hist = results["histories"]
    groups = [g for p in LOAD_PREFIXES for g in sorted(hist) if g.startswith(p)]
    times = np.unique(np.concatenate([hist[g]["time"] for g in groups])) if groups \
        else np.zeros(0)
    names, cols = ["time [s]"], [times]
    for g in groups:
        h = hist[g]
        rows = np.searchsorted(times, h["time"])
        for key in sorted(k for k in h if k != "time"):
            for name, values in _columns_of(g, key, h[key]):
                col = np.full(times.size, np.nan)
                col[rows] = values
                names.append(name)
                cols.append(col)
    return names, np.column_stack(cols) if cols[0].size else np.zeros((0, len(names)))


def write_csv(results: dict, path: str | os.PathLike) -> list[str]:
    """Write the per-step histories (:func:`history_table`) to one CSV file.

    Parameters
    ----------
    results
        :func:`pdfem.post.load.load_results` of a file.
    path
        The CSV file to write (overwritten). One header line of column names with units, then
        one line per step; numbers with 17 significant digits (they read back exactly), NaN
        as ``nan``.

    Returns
    -------
    list of str
        The column names.
    """
    names, table = history_table(results)
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        np.savetxt(fh, table, fmt="%.17g", delimiter=",", header=",".join(names), comments="")
    return names
