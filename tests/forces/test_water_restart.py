"""A run with water drag and added mass restarted from a mid-way checkpoint gives the energy
history of the uninterrupted run bit for bit (the water's drag loss and kinetic-energy counters
are checkpointed, :meth:`pdfem.forces.water.Water.checkpoint_state`).

Reference: the uninterrupted run of the same case (same machine; the kernels are
deterministic). A block released 2 cm above its floating draught heaves under buoyancy with
linear and quadratic drag and added mass, so every water counter is non-zero by the checkpoint.
"""

from __future__ import annotations

import shutil

import numpy as np

from pdfem.case.schema import load_case
from pdfem.output import read_results
from pdfem.run.checkpoint import CHECKPOINT_NAME
from pdfem.run.driver import run_case

CASE = """
[run]
end_time = 0.12
output_interval = 0.01
checkpoint_interval_steps = 0
safety_factor = 0.8

[water]
density = 1025.0
linear_drag = 2.0
drag_coefficient = 1.0
added_mass = 0.5

[[ice]]
name = "block"
dx = 0.05
shape = { box = { min = [0.0, 0.0, -0.199512], max = [0.2, 0.2, 0.050488] } }
material = { density = 900.0, youngs_modulus = 1.0e7, poisson_ratio = 0.3, fracture_energy = 1.0e6 }
"""


def test_water_drag_restart_bit_identical(tmp_path):
    """The energy history (drag loss, water potential and kinetic energy, residual) of a
    restarted run equals the uninterrupted run's bit for bit."""
    probe = tmp_path / "probe.toml"
    probe.write_text(CASE)
    steps = run_case(load_case(probe), tmp_path / "probe", quiet=True).steps
    every = max(steps // 2, 1)
    (tmp_path / "case.toml").write_text(CASE.replace("checkpoint_interval_steps = 0",
                                                     f"checkpoint_interval_steps = {every}"))
    case = load_case(tmp_path / "case.toml")
    ref = run_case(case, tmp_path / "ref", quiet=True)
    assert ref.steps == steps and every < steps
    shutil.copytree(tmp_path / "ref", tmp_path / "again")
    run_case(case, tmp_path / "again", quiet=True,
             restart=tmp_path / "again" / CHECKPOINT_NAME)
    a, b = read_results(ref.results), read_results(tmp_path / "again" / "results.h5")
    energy = a["histories"]["energy"]
    assert energy["water_drag_dissipated"][-1] > 0
    for k, v in energy.items():
        np.testing.assert_array_equal(v, b["histories"]["energy"][k], err_msg=k)
    np.testing.assert_array_equal(a["ice"]["block"]["u"], b["ice"]["block"]["u"])
