"""The results of a run as a Python object: histories as numpy arrays with units, the summary,
the frames' fields.

:class:`Results` wraps a results file read by :func:`pdfem.post.load_results` (the whole file,
as ``pdfem post`` reads it): ``time`` (the frames' times, s); the per-step histories by kind
(``loads``, ``regions``, ``patches``, ``contacts``, ``shaft``, ``motions``, ``monitors``; per
frame ``structures`` and ``energy``), each a :class:`History` of numpy arrays whose ``units``
name the unit of each column; ``summary``, the figures ``pdfem post --json`` prints
(:func:`pdfem.post.summarize`); and ``frame(i)``, the fields of output frame ``i``. SI units
throughout (:data:`pdfem.output.source.UNITS`).
"""

from __future__ import annotations

import os
from functools import cached_property
from pathlib import Path
from typing import Iterator, Mapping

import numpy as np

from pdfem.output.layout import CONSTANT_DATASETS
from pdfem.output.source import UNITS
from pdfem.post import load_results, summarize
from pdfem.post.groups import histories_of, patch_loads, split_loads


def unit_of(key: str) -> str:
    """The SI unit of a field or history column (``"force"`` -> ``"N"``; ``""`` if unknown)."""
    return UNITS.get(key) or (UNITS["reaction_<group>"] if key.startswith("reaction_") else "")


class History(Mapping[str, np.ndarray]):
    """One history of a results file: its columns by key, ``time`` (s) among them.

    Parameters
    ----------
    name
        The history's group in the file, e.g. ``loads/panel``.
    columns
        ``{key: (K, ...) array}``, one row per sample; ``time`` is (K,).
    """

    def __init__(self, name: str, columns: Mapping[str, np.ndarray]) -> None:
        self.name = name
        self.columns = dict(columns)

    @property
    def time(self) -> np.ndarray:
        """(K,) sample times, s."""
        return self.columns["time"]

    @property
    def units(self) -> dict[str, str]:
        """``{key: SI unit}`` of the columns."""
        return {k: "s" if k == "time" else unit_of(k) for k in self.columns}

    def __getitem__(self, key: str) -> np.ndarray:
        return self.columns[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.columns)

    def __len__(self) -> int:
        return len(self.columns)

    def __repr__(self) -> str:
        cols = ", ".join(f"{k} [{u}]" for k, u in self.units.items() if k != "time")
        return f"History({self.name!r}, {self.time.size} samples: {cols})"


class Results:
    """A run's results (module docstring): open one with :func:`pdfem.open_results`.

    Parameters
    ----------
    data
        :func:`pdfem.post.load_results` of the file.
    """

    def __init__(self, data: dict) -> None:
        self.data = data
        self.path = Path(data["file"])
        self.run_summary = None
        """The :class:`pdfem.run.driver.RunSummary` of a run made by :func:`pdfem.run`."""

    @property
    def meta(self) -> dict:
        """``/meta`` of the file: version, units, the case text (``case``), ranks, time step."""
        return self.data["meta"]

    @property
    def time(self) -> np.ndarray:
        """(F,) times of the output frames, s."""
        return self.data["time"]

    @cached_property
    def histories(self) -> dict[str, History]:
        """Every history of the file by group (``loads/<name>``, ``energy``, ...)."""
        return {g: History(g, cols) for g, cols in sorted(self.data["histories"].items())}

    def _of(self, groups: Mapping[str, dict], kind: str) -> dict[str, History]:
        return {n: self.histories[f"{kind}/{n}"] for n in groups}

    def _prefixed(self, kind: str) -> dict[str, History]:
        prefix = kind + "/"
        return {g[len(prefix):]: h for g, h in self.histories.items() if g.startswith(prefix)}

    @property
    def loads(self) -> dict[str, History]:
        """The ice load on each structure, every coupling step: ``force`` (K, 3) N, ``moment``
        (K, 3) N m about the origin, ``contacts``, ``applied`` (K, 3) N."""
        return self._of(split_loads(self.data["histories"])[0], "loads")

    @property
    def regions(self) -> dict[str, History]:
        """The reaction ``force`` (K, 3) N of each fixed or prescribed ice region
        (``<body>.<region>``): the force its support or driver exerts on the ice."""
        return self._of(split_loads(self.data["histories"])[1], "loads")

    @property
    def patches(self) -> dict[str, History]:
        """The ice ``force`` (K, 3) N on each load patch (``<structure>.<group>``) and its
        ``area`` (m^2)."""
        return self._of(patch_loads(self.data["histories"]), "loads")

    @property
    def contacts(self) -> dict[str, History]:
        """The ice load in each contact pair, as :attr:`loads`."""
        return self._of(histories_of(self.data["histories"], "contacts", "force"), "contacts")

    @property
    def monitors(self) -> dict[str, History]:
        """The probes: ``u`` (K, 3) m, ``von_mises`` and ``stress`` (K, 6) Pa."""
        return self._prefixed("monitors")

    @property
    def shaft(self) -> dict[str, History]:
        """Shaft loads of rotating structures (``<name>`` and ``<name>.<blade>``): torques
        (N m), thrust (N), power (W) ... every coupling step."""
        return self._prefixed("shaft")

    @property
    def motions(self) -> dict[str, History]:
        """The motion of free ships: ``position`` (m), ``rotation`` (rad), velocities."""
        return self._prefixed("motions")

    @property
    def structures(self) -> dict[str, History]:
        """Per structure and frame: kinetic and strain energy (J), support reactions (N)."""
        return self._prefixed("structures")

    @property
    def energy(self) -> History:
        """The energy balance per frame (J): every term, ``supplied``, ``stored``,
        ``dissipated`` and ``residual``."""
        return self.histories["energy"]

    @cached_property
    def summary(self) -> dict:
        """The summary ``pdfem post --json`` prints (:func:`pdfem.post.summarize`): peak and
        mean loads, peak stress and where, resistance, damage, energies (SI units)."""
        return summarize(self.data)

    def frame(self, i: int) -> dict[str, dict[str, np.ndarray]]:
        """The fields of output frame ``i`` (negative counts from the end).

        Returns
        -------
        dict
            ``{"ice/<body>": {...}, "structure/<name>": {...}}``: per ice body the reference
            positions ``x0`` (m) and the frame's ``u`` (m), ``v`` (m/s), ``damage`` (-), ...;
            per structure its mesh (``points`` m, ``cells``) and the frame's ``u`` (m),
            ``v`` (m/s), ``von_mises`` (Pa, per element), ...

        Raises
        ------
        IndexError
            If the file has no frame ``i``.
        """
        n = self.time.size
        if not -n <= i < n:
            raise IndexError(f"frame {i} of a results file with {n} frames")
        out = {}
        for group in ("ice", "structure"):
            for name, fields in self.data[group].items():
                out[f"{group}/{name}"] = {
                    k: a if k in CONSTANT_DATASETS or k == "cell_type" else a[i]
                    for k, a in fields.items()}
        return out

    def __repr__(self) -> str:
        kinds = ", ".join(f"{k} {sorted(v)}" for k, v in (
            ("loads", self.loads), ("regions", self.regions), ("contacts", self.contacts),
            ("monitors", self.monitors), ("shaft", self.shaft)) if v)
        return f"Results({str(self.path)!r}, {self.time.size} frames; {kinds or 'no loads'})"


def open_results(path: str | os.PathLike) -> Results:
    """The results of a run (module docstring).

    Parameters
    ----------
    path
        The ``results.h5`` a run wrote, or the run's output directory holding it.

    Raises
    ------
    InputError
        If there is no results file there, or it is not one (:func:`pdfem.post.load_results`).
    """
    p = Path(path)
    return Results(load_results(p / "results.h5" if p.is_dir() else p))
