"""Fatigue at monitors (``pdfem post --sn``): rainflow counting and the Palmgren-Miner sum.

References: ASTM E1049-85 (reapproved 2017), "Standard practices for cycle counting in fatigue
analysis", sec. 5.4.4 and its rainflow example (Fig. 6 / Table 4); DNV-RP-C203 (2016),
"Fatigue design of offshore steel structures", Table 2-1 (the D curve in air); the Miner sum
``D = sum n_i / N_i`` worked by hand; Euler-Bernoulli bending stress of a cantilever and the
dynamic load factor 2 of a suddenly applied, held load on an undamped oscillator (Clough &
Penzien, Dynamics of Structures, 1993, sec. 4-1).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from pdfem.case.schema import load_case
from pdfem.cli import main as cli
from pdfem.errors import InputError
from pdfem.post.fatigue import (SNCurve, counted_stress, fatigue_figures, miner_damage,
                                parse_sn, rainflow_cycles)
from pdfem.run.driver import run_case

from support.results import write_swinging_monitor

D_CURVE = "m=3,stress=90e6,cycles=2e6,m2=5,knee=1e7"  # DNV-RP-C203 D curve in air, FAT 90
BOX = Path(__file__).resolve().parents[2] / "models" / "validation" / "box.py"


def run_post(capsys, *args) -> tuple[int, str, str]:
    """``pdfem post ...`` in this process: (exit status, stdout, stderr)."""
    capsys.readouterr()
    rc = cli.main(["post", *map(str, args)])
    out = capsys.readouterr()
    return rc, out.out, out.err


def test_astm_e1049_rainflow_example():
    """ASTM E1049-85 Fig. 6 / Table 4: the history -2, 1, -3, 5, -1, 3, -4, 4, -2 holds
    ranges 3 (0.5 cycle), 4 (1.5), 6 (0.5), 8 (1.0) and 9 (0.5)."""
    series = np.array([-2, 1, -3, 5, -1, 3, -4, 4, -2], dtype=float)
    cycles = rainflow_cycles(np.arange(series.size, dtype=float), series)
    counts: dict[float, float] = {}
    for r, c in cycles[:, [0, 2]]:
        counts[r] = counts.get(r, 0.0) + c
    assert counts == {3.0: 0.5, 4.0: 1.5, 6.0: 0.5, 8.0: 1.0, 9.0: 0.5}
    # the one full cycle of range 4 is -1 -> 3 (mean 1), between t = 4 and t = 5
    full = cycles[cycles[:, 2] == 1.0]
    assert full[full[:, 0] == 4.0].tolist() == [[4.0, 1.0, 1.0, 4.0, 5.0]]


def test_miner_sum_of_constant_amplitude_is_n_over_N():
    """n = 1000 cycles of range 100 MPa on FAT 90 (m = 3): N = 2e6 (90/100)^3, D = n / N."""
    n, ds, mean = 1000, 100e6, 40e6
    k = np.arange(2 * n + 1)
    series = mean + 0.5 * ds * (-1.0) ** k
    cycles = rainflow_cycles(k * 1e-3, series)
    assert cycles[:, 2].sum() == pytest.approx(n, abs=1e-12)
    np.testing.assert_allclose(cycles[:, 0], ds)
    np.testing.assert_allclose(cycles[:, 1], mean)
    curve = parse_sn("m=3,stress=90e6,cycles=2e6")
    expected = n / (2e6 * (90.0 / 100.0) ** 3)
    assert miner_damage(cycles, curve).sum() == pytest.approx(expected, rel=1e-12)
    f = fatigue_figures(cycles, curve, events=365.0)
    assert f["damage"] == pytest.approx(expected, rel=1e-12)
    assert f["damage_total"] == pytest.approx(365.0 * expected, rel=1e-12)
    assert f["life_events"] == pytest.approx(1.0 / expected, rel=1e-12)
    assert sum(h["cycles"] for h in f["histogram"]) == pytest.approx(n)


def test_two_slope_curve_is_dnv_d_curve_in_air():
    """DNV-RP-C203 Table 2-1, D in air: log a1 = 12.164 (m1 = 3, N <= 1e7), log a2 = 15.606
    (m2 = 5), fatigue limit 52.63 MPa at 1e7 cycles; a for ranges in MPa."""
    curve = parse_sn(D_CURVE)
    assert curve.as_dict()["log10_a_MPa"] == pytest.approx(12.164, abs=5e-4)
    assert curve.knee_range == pytest.approx(52.63e6, rel=1e-4)
    for s_mpa in (200.0, 100.0, 60.0):
        assert curve.endurance(np.array([s_mpa * 1e6]))[0] == pytest.approx(
            10 ** (12.164 - 3 * math.log10(s_mpa)), rel=2e-3)
    for s_mpa in (50.0, 30.0, 10.0):
        assert curve.endurance(np.array([s_mpa * 1e6]))[0] == pytest.approx(
            10 ** (15.606 - 5 * math.log10(s_mpa)), rel=2e-3)
    # Miner sum across the knee: 1e6 cycles at 100 MPa and 1e8 at 30 MPa
    cycles = np.array([[100e6, 0.0, 1e6, 0.0, 1.0], [30e6, 0.0, 1e8, 1.0, 2.0]])
    n1 = 2e6 * 0.9 ** 3
    n2 = 1e7 * (90.0 * 0.2 ** (1 / 3) / 30.0) ** 5
    assert miner_damage(cycles, curve).sum() == pytest.approx(1e6 / n1 + 1e8 / n2, rel=1e-12)
    assert curve.endurance(np.array([0.0]))[0] == math.inf


def test_principal_stress_is_signed_and_von_mises_is_not():
    """A uniaxial stress reversing from +s to -s: the principal stress of largest magnitude
    ranges over 2 s; von Mises stays at s (no range), which is why it is not the default."""
    s = 50e6
    stress = np.zeros((5, 6))
    stress[:, 0] = s * np.array([1.0, -1.0, 1.0, -1.0, 1.0])
    h = {"time": np.arange(5.0), "stress": stress, "von_mises": np.full(5, s)}
    p = counted_stress(h, "principal")
    np.testing.assert_allclose(p, stress[:, 0], rtol=1e-12)
    assert rainflow_cycles(h["time"], p)[:, 0].max() == pytest.approx(2 * s)
    assert rainflow_cycles(h["time"], counted_stress(h, "von_mises")).size == 0
    # pure shear xy = t: principals +t and -t, the first of largest magnitude; yz component
    shear = np.zeros((1, 6))
    shear[0, 5] = 3e6
    assert abs(counted_stress({"stress": shear}, "principal")[0]) == pytest.approx(3e6)
    assert counted_stress({"stress": shear}, "xy")[0] == 3e6


@pytest.mark.parametrize("text, says", [
    ("m=3,stress=90,cycles=2e6", "MPa given"),
    ("m=3,stress=90e6", "cycles missing"),
    ("m=3,stress=90e6,cycles=2e6,slope=5", "not one of the keys"),
    ("m=-3,stress=90e6,cycles=2e6", "m must be a positive number"),
    ("m=3,stress=abc,cycles=2e6", "stress must be a positive number"),
    ("m=3,stress=90e6,cycles=2e6,knee=1e7", "knee needs the slope m2"),
])
def test_bad_sn_text_names_the_option(text, says):
    with pytest.raises(InputError) as err:
        parse_sn(text, "results.h5")
    assert "'--sn'" in str(err.value) and says in str(err.value)


@pytest.fixture(scope="module")
def small_file(tmp_path_factory) -> Path:
    """A hand-made results file: monitor 'root' with xx = 40 MPa +- 50 MPa, 10 cycles."""
    return write_swinging_monitor(tmp_path_factory.mktemp("fatigue") / "results.h5")


@pytest.mark.parametrize("args, option", [
    (["--sn", "m=3,stress=90,cycles=2e6"], "--sn"),
    (["--sn", "m=3"], "--sn"),
    (["--sn", D_CURVE, "--sn-monitor", "nowhere"], "--sn-monitor"),
    (["--sn", D_CURVE, "--sn-stress", "tresca"], "--sn-stress"),
    (["--sn", D_CURVE, "--events", "0"], "--events"),
    (["--events", "10"], "--events"),
])
def test_bad_fatigue_options_exit_2(small_file, capsys, args, option):
    rc, out, err = run_post(capsys, small_file, *args)
    assert rc == 2 and "Traceback" not in err
    assert f"field '{option}'" in err and str(small_file) in err


def test_fatigue_text_csv_and_plot(small_file, tmp_path, capsys):
    """10 cycles of 100 MPa on FAT 90: D = 10 / (2e6 * 0.9^3) in the table, CSV and plot."""
    rc, out, _ = run_post(capsys, small_file, "--sn", D_CURVE, "--events", "100",
                          "--csv", tmp_path / "h.csv", "--plots", tmp_path / "plots")
    assert rc == 0
    d = 10 / (2e6 * 0.9 ** 3)
    assert "monitor 'root': 10 cycles" in out and f"damage {d:.4g}" in out
    rows = (tmp_path / "h_rainflow.csv").read_text().splitlines()
    assert rows[0].startswith("monitor,range_low [Pa]")
    cols = np.array([[float(c or "nan") for c in r.split(",")[1:]] for r in rows[1:]])
    assert cols[:, 2].sum() == pytest.approx(10.0) and cols[:, 4].sum() == pytest.approx(d)
    png = tmp_path / "plots" / "fatigue_root.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


CANTILEVER = """
[run]
title = "fatigue: cantilever under a suddenly applied tip load"
end_time = 1.4e-2          # s: a little more than one period of the first mode (12 ms)
output_interval = 7.0e-3
safety_factor = 0.9

[[structure]]
name = "beam"
kind = "elastic"
mesh = "{box}"
params = {{ length_x = 1.0, length_y = 0.1, length_z = 0.1, divisions_x = 20, divisions_y = 2, divisions_z = 2, fixed_faces = "x0", loaded_faces = "x1", contact_faces = "" }}
material = {{ density = 7850.0, youngs_modulus = 210e9, poisson_ratio = 0.3 }}
fixed_groups = ["fixed"]
contact_group = "loaded"
loads = [ {{ group = "loaded", traction = [0.0, 0.0, -1.0e5] }} ]

[[monitor]]
name = "top"
structure = "beam"
point = [0.525, 0.05, 0.1]   # the element centred at x = 0.525 m, z = 0.075 m
"""


def test_end_to_end_cantilever_fatigue_block(tmp_path, capsys):
    """A 1 m steel cantilever (0.1 m square) with 1 kN put on its tip at t = 0 and held:
    the bending stress at x = 0.525 m, 0.025 m above the neutral axis, is
    P (L - x) z / I = 1.425 MPa statically and swings between 0 and twice that (dynamic load
    factor 2): one rainflow range of about 2.85 MPa dominates the Miner sum."""
    case = tmp_path / "beam.toml"
    case.write_text(CANTILEVER.format(box=BOX.as_posix()))
    results = run_case(load_case(case), tmp_path / "out", quiet=True).results
    rc, out, _ = run_post(capsys, results, "--json", "--sn", D_CURVE)
    assert rc == 0
    fatigue = json.loads(out)["fatigue"]
    assert fatigue["stress"] == "principal"
    assert fatigue["curve"]["knee_range"] == pytest.approx(52.63e6, rel=1e-4)
    top = fatigue["monitors"]["top"]
    static = 1e3 * (1.0 - 0.525) * 0.025 / (0.1 ** 4 / 12)
    assert top["max_range"] == pytest.approx(2 * static, rel=0.08)
    big = top["largest"][0]
    assert big["range"] == top["max_range"]
    n_big = SNCurve(3, 90e6, 2e6, 5, 1e7).endurance(np.array([big["range"]]))[0]
    assert big["count"] / n_big == pytest.approx(top["damage"], rel=0.05)
    assert top["life_events"] == pytest.approx(1 / top["damage"])
