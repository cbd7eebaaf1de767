"""``pdfem run CASE --profile``: where the time of a run goes, by component.

Reference: the loop's own wall time. Every wrapped call is booked to its component only (the
time of wrapped calls made inside it is taken out), so the components add up to the loop's
wall time exactly (to round-off), none is negative, and the parts the case has are there: an
ice block (bonds) striking an elastic plate (surface contact, structures) under gravity.
"""

from __future__ import annotations

import json
import time

import pytest

from pdfem.case.schema import load_case
from pdfem.parallel.comm import SerialComm
from pdfem.run.driver import run_case
from pdfem.run.profile import PROFILE_NAME, Profile

from support.cli import run_ok

CASE = """
[run]
end_time = 2.0e-4
output_interval = 1.0e-4
gravity = [0.0, 0.0, -9.81]
[[ice]]
name = "block"
dx = 0.02
shape = { box = { min = [-0.06, -0.06, 0.0005], max = [0.06, 0.06, 0.0805] } }
material = { fracture_energy = 10.0 }
initial_velocity = [0.0, 0.0, -2.0]
[[structure]]
name = "plate"
mesh = "box.py"
params = { origin_x = -0.2, origin_y = -0.2, origin_z = -0.02, length_x = 0.4, length_y = 0.4, length_z = 0.02, divisions_x = 4, divisions_y = 4, divisions_z = 1, fixed_faces = "x0", contact_faces = "z1" }
fixed_groups = ["fixed"]
contact_group = "contact"
[[contact]]
ice = "block"
structure = "plate"
"""


def _case(tmp_path):
    import shutil
    from pathlib import Path

    box = Path(__file__).resolve().parents[2] / "models" / "validation" / "box.py"
    shutil.copy(box, tmp_path / "box.py")
    path = tmp_path / "case.toml"
    path.write_text(CASE)
    return path


def test_components_add_up_to_the_loop(tmp_path):
    summary = run_case(load_case(_case(tmp_path)), tmp_path / "out", quiet=True, profile=True)
    rows = {r["component"]: r for r in summary.profile}
    total = rows.pop("total")
    assert total["seconds"] > 0 and total["share"] == 1.0
    assert {"bonds and failure", "surface contact", "contact surfaces", "structures",
            "gravity", "coupling (rest)", "histories", "frames and checkpoints",
            "loop (rest)"} <= set(rows)
    assert sum(r["seconds"] for r in rows.values()) == pytest.approx(total["seconds"], rel=1e-9)
    assert all(r["seconds"] >= 0.0 for r in rows.values())
    for r in ("bonds and failure", "surface contact", "structures"):
        assert rows[r]["seconds"] > 0.0
    particle_steps = summary.particles * summary.steps
    assert total["per_particle_step"] == pytest.approx(total["seconds"] / particle_steps)
    assert json.loads((tmp_path / "out" / PROFILE_NAME).read_text()) == summary.profile
    assert "ns/particle-step" in summary.text()


def test_a_call_inside_a_timed_call_is_booked_to_its_own_component(monkeypatch):
    """Exclusive times: the outer call's own time is its wall time less the inner call's. The
    clock is a counter the calls advance (0.02 s inner, 0.01 s outer), so the booking is
    checked exactly, whatever the machine's load."""
    now = [100.0]
    monkeypatch.setattr(time, "perf_counter", lambda: now[0])

    class Work:
        def inner(self):
            now[0] += 0.02

        def outer(self):
            now[0] += 0.01
            self.inner()

    w, p = Work(), Profile()
    p.wrap(w, "inner", "inner")
    p.wrap(w, "outer", "outer")
    w.outer()
    assert p.seconds["inner"] == pytest.approx(0.02, abs=1e-12)
    assert p.seconds["outer"] == pytest.approx(0.01, abs=1e-12)
    rows = p.rows(SerialComm(), particles=10, steps=2, ice_steps=2)
    assert rows[-1]["component"] == "total"


@pytest.mark.slow
def test_cli_profile_in_the_json_summary(tmp_path):
    path = _case(tmp_path)
    r = run_ok("run", path, "--out", tmp_path / "out", "--profile", "--json", timeout=300)
    report = json.loads(r.stdout)
    names = [row["component"] for row in report["profile"]]
    assert names[-1] == "total" and "bonds and failure" in names


def test_no_ice_no_particle_step_figure():
    """A run without ice (a structure alone) has no particle-steps: the column says so."""
    from pdfem.run.profile import table

    p = Profile()
    p.seconds["structures"] = 1.0
    p.loop = 1.5
    rows = p.rows(SerialComm(), particles=0, steps=10, ice_steps=10)
    assert all(r["per_particle_step"] is None for r in rows)
    assert rows[-1]["seconds"] == 1.5 and rows[-1]["per_step"] == pytest.approx(0.15)
    assert table(rows, 0)[-1].rstrip().endswith("-")
