"""A small hand-made results file for the tests of ``pdfem post``."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pdfem.output import ResultsWriter


def write_swinging_monitor(path: Path, title: str = "fatigue") -> Path:
    """Write ``path``: one elastic tetrahedron 'panel' at rest and a monitor 'root' whose xx
    stress swings 40 MPa +- 50 MPa, 10 cycles over 21 steps of 1 ms; returns ``path``."""
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    with ResultsWriter(path, "", {"title": title}) as w:
        w.add_structure("panel", points, np.array([[0, 1, 2, 3]]), "tetra")
        w.write_frame(0.0, {}, {"panel": {"u": np.zeros((4, 3)), "von_mises": np.zeros(1)}})
        for k in range(21):
            sxx = 40e6 + 50e6 * (-1.0) ** k
            w.append_history("monitors/root", k * 1e-3, {
                "u": [0.0, 0.0, 0.0], "von_mises": abs(sxx),
                "stress": [sxx, 0.0, 0.0, 0.0, 0.0, 0.0]})
    return path
