"""The coupling step and the substeps of a run (pdfem.run.timesteps) at the ends of the range
(issue 31): a side whose step is longer than the whole run, and the step-count limit.

Reference: the substep rule of :func:`pdfem.coupling.coupler.substep_counts` (the faster side
takes floor(slow / fast) steps of the slower side's step), with the coupling step at most the
end time, so the faster side takes end_time / its step steps in all.
"""

from __future__ import annotations

import pytest

from pdfem.case.schema import load_case
from pdfem.errors import InputError
from pdfem.run.step_limits import MAX_STEPS
from pdfem.run.timesteps import choose_time_steps

CASE = """[run]
end_time = 1e-5

[[ice]]
name = "floe"
dx = 0.05
shape = { box = { min = [0.0, 0.0, 0.0], max = [0.2, 0.2, 0.2] } }
"""


class _Side:
    """A body or a structure with a fixed stable step (s)."""

    def __init__(self, name: str, step: float):
        self.name, self.step = name, step

    def stable_time_step(self) -> float:
        return self.step

    def critical_time_step(self) -> float:
        return self.step / 0.8  # safety_factor 0.8 makes the usable step ``step``


def _case(tmp_path, extra: str = ""):
    path = tmp_path / "case.toml"
    path.write_text(CASE.replace("end_time = 1e-5", "end_time = 1e-5\n" + extra))
    return load_case(path)


def test_a_side_slower_than_the_run_steps_once_and_the_other_to_the_end(tmp_path):
    """An ice step of 1e150 s (ice of no stiffness) over a structure step of 1e-6 s: one
    coupling step of end_time = 1e-5 s with 10 structure substeps (it was 1e156 substeps)."""
    case = _case(tmp_path)
    dt, n_ice, n_st = choose_time_steps(case, [_Side("floe", 1.25e150)], [_Side("wall", 1e-6)])
    assert (dt, n_ice, n_st) == (pytest.approx(1e-5, rel=1e-12), 1, 10)


def test_more_steps_than_the_limit_are_refused_naming_the_cause(tmp_path):
    """end_time / step > MAX_STEPS: safety_factor is named when 0.8 would do; end_time when
    the material is a solid's and the step is usual."""
    with pytest.raises(InputError) as e:
        choose_time_steps(_case(tmp_path, "safety_factor = 1e-9"), [_Side("floe", 1e-6)], [])
    assert e.value.field == "run.safety_factor"
    step = 1e-5 / MAX_STEPS  # exactly MAX_STEPS steps of the usable step pass
    assert choose_time_steps(_case(tmp_path), [_Side("floe", step / 0.8)], [])[0] == \
        pytest.approx(step)
    with pytest.raises(InputError) as e:
        choose_time_steps(_case(tmp_path), [_Side("floe", step / 0.8 / 2)], [])
    assert e.value.field == "run.end_time" and "choose end_time <=" in str(e.value)
