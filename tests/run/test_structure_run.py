"""A structure-only case run from the command line: the hull panel under a pressure pulse.

References: static equilibrium (the support reactions balance the pressure resultant p x A once
the response has settled), and the XDMF file read back through its data items (tests/support/xdmf.py).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pdfem.output import read_results

from support.xdmf import read_xdmf

P = 2.0e5  # Pa
LENGTH, BREADTH = 2.0, 1.2  # m, the hull panel's plating (models/hull_panel.py defaults)

CASE = f"""
[run]
end_time = 6.0e-3
output_interval = 5.0e-4

[[structure]]
name = "panel"
mesh = "hull_panel"
params = {{ element_size = 0.1, element_type = "tet" }}
material = {{ density = 7850.0, youngs_modulus = 210e9, poisson_ratio = 0.3 }}
fixed_groups = ["fixed"]
element_order = 1   # first-order tetrahedra: this file pins their layout (tetra cells)
contact_group = "contact"
damping = {{ alpha = 8000.0 }}   # 1/s, about critical for the panel's first mode (~600 Hz)
loads = [ {{ group = "contact", pressure = {P}, pulse = {{ start = 0.0, rise = 1.0e-3, hold = 10.0, fall = 1.0e-3 }} }} ]
"""


def _pdfem(*args):
    script = Path(sys.executable).parent / "pdfem"
    command = [str(script)] if script.exists() else [sys.executable, "-m", "pdfem"]
    return subprocess.run([*command, *args], capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def panel_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("panel")
    case = d / "panel.toml"
    case.write_text(CASE)
    r = _pdfem("run", str(case), "--out", str(d / "out"), "--json")
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.mark.slow
def test_supports_balance_the_pressure_resultant(panel_run):
    """After the load has risen (1 ms) and the damped response settled, the reaction at the
    clamped boundary equals p x A upward (Newton's static equilibrium), within 1 %; the panel
    deflects into the hull (-z) and is stressed."""
    r = read_results(panel_run["results"])
    hist = r["histories"]["structures/panel"]
    reaction = hist["reaction_fixed"][-1]
    assert reaction[2] == pytest.approx(P * LENGTH * BREADTH, rel=0.01)
    assert abs(reaction[0]) < 1e-3 * reaction[2] and abs(reaction[1]) < 1e-3 * reaction[2]
    assert hist["kinetic"][-1] < 1e-3 * hist["strain"][-1]  # settled
    u = r["structure"]["panel"]["u"][-1]
    assert u[:, 2].min() < 0 and u[:, 2].max() <= 1e-3 * abs(u[:, 2].min())
    assert r["structure"]["panel"]["von_mises"][-1].max() > 0


def test_structure_results_layout_and_xdmf(panel_run):
    """The results file holds the design's structure layout (points, cells, u per frame,
    von_mises per element and frame) and the XDMF file shows the panel's tetrahedra where they
    are (points + u) with u at the nodes and von_mises on the cells."""
    path = Path(panel_run["results"])
    r = read_results(path)
    s = r["structure"]["panel"]
    nf = r["time"].shape[0]
    assert nf == panel_run["frames"] == 13
    nn, ne = s["points"].shape[0], s["cells"].shape[0]
    assert s["cell_type"] == "tetra" and s["cells"].shape == (ne, 4)
    assert s["u"].shape == (nf, nn, 3) and s["von_mises"].shape == (nf, ne)
    frames = read_xdmf(path.with_suffix(".xdmf"))["structure/panel"]
    assert len(frames) == nf and frames[-1].time == r["time"][-1]
    grid = frames[-1].grids["structure/panel"]
    assert grid.topology == "Tetrahedron"
    np.testing.assert_array_equal(grid.cells, s["cells"])
    np.testing.assert_array_equal(grid.points, s["points"] + s["u"][-1])
    np.testing.assert_array_equal(grid.point_data["u"], s["u"][-1])
    np.testing.assert_array_equal(grid.cell_data["von_mises"], s["von_mises"][-1])
