"""Blow-up detection: a run with three times the stable step stops with exit 3, a diagnosis and
its results kept.

References: the stability limit of velocity Verlet (a step above 2/omega_max makes the highest
mode grow without bound), which :meth:`pdfem.pd.body.IceBody.stable_time_step` bounds from
below; energy conservation (nothing does work on a free body, so its energy cannot grow).
"""

from __future__ import annotations

import re

from types import SimpleNamespace

import numpy as np
import pytest

from pdfem.run.blowup import BlowupMonitor
from pdfem.case.schema import parse_case
from pdfem.errors import InstabilityError
from pdfem.output import read_results
from pdfem.run.build_ice import build_ice_body

from support.cli import run_pdfem

CASE = """
[run]
end_time = {end}
output_interval = {out}
time_step = {dt}
allow_unstable_time_step = {allow}

[[ice]]
name = "bar"
dx = 0.01
shape = {{ box = {{ min = [0, 0, 0], max = [0.2, 0.04, 0.04] }} }}
initial_velocity = [0.0, 0.0, 1.0]
fixed = [ {{ box = {{ min = [0, 0, 0], max = [0.02, 0.04, 0.04] }} }} ]
"""


def _stable_step() -> float:
    case = parse_case(CASE.format(end=1e-3, out=1e-4, dt=0.0, allow="false"))
    return build_ice_body(case.ice[0], case.run).stable_time_step()


def test_three_times_the_stable_step_exits_3_with_results_kept(tmp_path):
    """time_step = 3 x stable: exit 3; the message names the body, the quantity and suggests a
    smaller step; the results file reads, with the frames written before the failure."""
    dt = 3.0 * _stable_step()
    case = tmp_path / "unstable.toml"
    case.write_text(CASE.format(end=400 * dt, out=20 * dt, dt=dt, allow="true"))
    r = run_pdfem("run", str(case), "--out", str(tmp_path / "o"))
    assert r.returncode == 3, r.stderr
    assert "Traceback" not in r.stderr
    assert "ice body 'bar'" in r.stderr and "smaller step" in r.stderr
    assert "3.00 x the stable estimate" in r.stderr
    assert "results so far are kept" in r.stderr
    res = read_results(tmp_path / "o" / "results.h5")
    t_fail = float(re.search(r"at t = ([0-9.eE+-]+) s", r.stderr).group(1))
    times = res["time"]
    assert times[0] == 0.0 and t_fail < 400 * dt  # stopped before the end of the run
    # every frame due before the failure is kept (one every 20 steps), none after it (t_fail
    # is printed to 7 significant digits)
    assert times.size >= int(t_fail / (20 * dt) * (1 + 1e-6)) and times[-1] <= t_fail * (1 + 1e-6)
    assert np.isfinite(res["ice"]["bar"]["u"]).all()


def test_unstable_time_step_is_bad_input_unless_allowed(tmp_path):
    """Without run.allow_unstable_time_step the same case is refused up front (exit 2), and the
    message names the field and the key that would allow it."""
    dt = 3.0 * _stable_step()
    case = tmp_path / "unstable.toml"
    case.write_text(CASE.format(end=400 * dt, out=20 * dt, dt=dt, allow="false"))
    r = run_pdfem("run", str(case), "--out", str(tmp_path / "o"))
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "run.time_step" in r.stderr and "allow_unstable_time_step" in r.stderr


def _body(v, delta=0.03):
    n = len(v)
    return SimpleNamespace(name="b", y=np.zeros((n, 3)), v=np.asarray(v, dtype=float),
                           x0=np.arange(3.0 * n).reshape(n, 3), delta=delta, n=n,
                           vol=np.full(n, 1e-6), material=SimpleNamespace(youngs_modulus=4e9))


def test_motion_check_speed_limit_and_nan():
    """A particle moving exactly one horizon per step passes, a little more is stopped; NaN is
    stopped and located (reference: the definition max |v| h <= delta)."""
    h = 1e-6
    ok = _body([[0.0, 0.0, 0.03 / h], [0.0, 0.0, 0.0]])
    BlowupMonitor([ok], h, {"b": h}, 1).check_motion(1e-3, 1)
    fast = _body([[0.0, 0.0, 0.0], [0.0, 0.031 / h, 0.0]])
    with pytest.raises(InstabilityError, match=r"particle 1 moves 3\.100e-02 m per step"):
        BlowupMonitor([fast], h, {"b": h / 2}, 1).check_motion(1e-3, 1)
    bad = _body([[0.0, 0.0, 0.0], [0.0, np.nan, 0.0]])
    with pytest.raises(InstabilityError, match="NaN/Inf.*particle 1.*2.00 x the stable"):
        BlowupMonitor([bad], h, {"b": h / 2}, 1).check_motion(1e-3, 1)
    BlowupMonitor([bad], h, {"b": h}, 5).check_motion(1e-3, 3)  # not a check step


def _row(supplied, residual, **terms):
    row = {"supplied": supplied, "residual": residual, "stored": supplied - residual,
           "contact_dissipated": 0.0, "fracture_dissipated": 0.0, "damping_dissipated": 0.0,
           "kinetic": supplied - residual, "strain": 0.0}
    row.update(terms)
    return row


def test_energy_check_threshold():
    """Energy created up to energy_tolerance (1 %) of the energy supplied plus the round-off
    floor (1/2 E V 1e-10) passes; more stops the run with the budget. A negative dissipation
    term counts as energy created (second law: dissipation only takes energy out)."""
    b = _body([[0.0, 0.0, 0.0]])
    m = BlowupMonitor([b], 1e-6, {"b": 1e-6}, 1)
    floor = 0.5 * 4e9 * 1e-6 * 1e-10
    assert m.energy_floor == pytest.approx(floor)
    m.check_energy(0.1, 10, _row(2.0, -(0.02 + 0.9 * floor)))
    m.check_energy(0.1, 10, _row(2.0, -(0.02 + 1.1 * floor)))   # crossed: maybe a transient
    m.check_energy(0.1, 10, _row(2.0, -(0.02 + 0.9 * floor)))   # back below: it was one
    m.check_energy(0.1, 10, _row(2.0, -(0.02 + 1.1 * floor)))   # crossed again
    with pytest.raises(InstabilityError, match=r"created energy.*1\.0\d* %.*it lasts.*budget"):
        m.check_energy(0.1, 10, _row(2.0, -(0.02 + 1.1 * floor)))  # nothing supplied: lasts
    with pytest.raises(InstabilityError, match="fracture_dissipated.*negative"):
        m.check_energy(0.1, 10, _row(2.0, 0.0, fracture_dissipated=-0.03))
    loose = BlowupMonitor([b], 1e-6, {"b": 1e-6}, 1, energy_tolerance=0.5)
    loose.check_energy(0.1, 10, _row(2.0, -0.9))  # 45 % created, 50 % allowed
    with pytest.raises(InstabilityError, match="NaN/Inf"):
        m.check_energy(0.1, 10, _row(2.0, np.nan))


def test_energy_guard_tells_transients_from_steady_creation():
    """Measured shapes (docs/ice_failure.md, "Energy guard"), floor 2e-4 J, tolerance 1 %:

    - a crushing onset: 0.088 J created at once while 3.6 J were supplied (2.4 %), then no
      more while the push supplies 1 J per check: it crossed the limit, its share falls, the
      run goes on;
    - steady creation: 1.2 % of every joule supplied after the crossing: stops with "keeps
      growing" once the growth beats the tolerance of the supply since the crossing + floor;
    - gross: 11 x the limit stops at once;
    - above the stable estimate the tolerance is halved (0.8 % created stops there, not
      below it)."""
    b = _body([[0.0, 0.0, 0.0]])
    m = BlowupMonitor([b], 1e-6, {"b": 1e-6}, 1)
    floor = m.energy_floor
    for k in range(20):                                  # onset, then the push goes on
        m.check_energy(0.1, k, _row(3.6 + k, -0.088))
    steady = BlowupMonitor([b], 1e-6, {"b": 1e-6}, 1)
    steady.check_energy(0.1, 0, _row(10.0, -0.11))       # 1.1 %: crossed
    supplied_then = 10.0
    with pytest.raises(InstabilityError, match="keeps growing"):
        for k in range(1, 100):
            s = 10.0 + k
            steady.check_energy(0.1, k, _row(s, -(0.11 + 0.012 * (s - supplied_then))))
    assert k * 0.002 > floor            # stopped once the excess growth passed the floor
    gross = BlowupMonitor([b], 1e-6, {"b": 1e-6}, 1)
    with pytest.raises(InstabilityError, match="10 x the limit"):
        gross.check_energy(0.1, 0, _row(1.0, -0.11 - 11 * floor))
    above = BlowupMonitor([b], 2e-6, {"b": 1e-6}, 1)     # ice step 2 x its stable estimate
    assert above.tolerance == 0.005 and m.tolerance == 0.01
    above.check_energy(0.1, 0, _row(100.0, -0.8))        # 0.8 %: crossed 0.5 %
    with pytest.raises(InstabilityError, match="halved.*it lasts"):
        above.check_energy(0.1, 1, _row(100.0, -0.8))
