"""Reading a results file back: :func:`read_results` loads it whole into numpy arrays.

For tests and post-processing (:mod:`pdfem.post`). It reads files of killed runs and files a
run is still writing, returning only what was committed (see :mod:`pdfem.output.writer`), and
puts the per-rank ice files of an MPI run together (:mod:`pdfem.output.ranks`).
"""

from __future__ import annotations

import os
from typing import Any

from pdfem.output.datasets import committed, readable_prefix
from pdfem.output.files import open_for_reading
from pdfem.output.layout import CONSTANT_DATASETS, attr_value, history_groups
from pdfem.output.ranks import merge_rank_files, rank_files


def read_results(path: str | os.PathLike) -> dict:
    """Load a results file into numpy arrays.

    Parameters
    ----------
    path
        The HDF5 results file. It may come from a killed run, or still be open in a running
        writer (a file locked by another process is then read without HDF5 file locking).

    Returns
    -------
    dict
        ``{"meta": {attr: value}, "time": (F,), "ice": {body: {"x0", "volume"?, "u", "v",
        "damage", ...}}, "structure": {name: {"points", "cells", "cell_type", "u",
        "von_mises"?, ...}}, "histories": {group: {"time": (K,), key: (K, ...)}}}``. Only
        committed rows are returned: F counts the rows of ``/time`` before the first NaN (a
        time row is written only after its frame's data was flushed), cut further to the
        frames that every field dataset can read; each history likewise (a run killed while
        writing may have extended some datasets and not others).

    Raises
    ------
    FileNotFoundError
        If the file's ``/meta`` names per-rank files (``ice_per_rank``) and one is missing.
    """
    out: dict[str, Any] = {"meta": {}, "time": None, "ice": {}, "structure": {},
                           "histories": {}}
    with open_for_reading(path) as f:
        out["meta"] = {k: attr_value(v) for k, v in f["meta"].attrs.items()}
        frames = {"time": committed(readable_prefix(f["time"], f["time"].shape[0]))}
        n = frames["time"].shape[0]
        for group in ("ice", "structure"):
            for name, g in f.get(group, {}).items():
                body = out[group].setdefault(name, {})
                for k, ds in g.items():
                    if k in CONSTANT_DATASETS:
                        body[k] = ds[()]
                        if k == "cells":
                            body["cell_type"] = attr_value(ds.attrs["cell_type"])
                    else:
                        frames[f"{group}/{name}/{k}"] = a = readable_prefix(ds, min(n, ds.shape[0]))
                        n = min(n, a.shape[0])
        out["time"] = frames.pop("time")[:n]
        for key, a in frames.items():
            group, name, k = key.split("/")
            out[group][name][k] = a[:n]
        for name, g in history_groups(f):
            rows = {k: readable_prefix(ds, ds.shape[0]) for k, ds in g.items()}
            rows["time"] = committed(rows["time"])
            k_min = min(a.shape[0] for a in rows.values())
            out["histories"][name] = {k: a[:k_min] for k, a in rows.items()}
    ranks = int(out["meta"].get("ice_per_rank", 0))
    if ranks:
        merge_rank_files(out, [read_results(file) for file in rank_files(path, ranks)])
    return out
