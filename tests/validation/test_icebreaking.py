"""The icebreaking case's pieces: Lindqvist's (1989) resistance against a hand computation, the
steady-phase figures of a resistance history, the tiny case and its validation entry. SI units.
(The simulation itself takes minutes: ``pdfem run models/validation/icebreaker_tiny.toml``.)"""

from __future__ import annotations

import math

import numpy as np
import pytest

from pdfem.post.lindqvist import lindqvist_resistance
from pdfem.post.resistance import (hull_names, resistance_history, steady_figures,
                                   steady_start)
from pdfem.validation.case import load_validation_case


def test_lindqvist_against_hand_computation():
    """Lindqvist (1989) by hand for the tiny case: L = 1.5, B = 0.3, T = 0.1 m, phi = 25 deg,
    alpha = 30 deg, h = 0.03 m, sigma_b = 40 kPa, E = 50 MPa, nu = 0.3, mu = 0.1,
    rho_w = 1000, rho_i = 900 kg/m^3, v = 0.5 m/s, g = 9.81 m/s^2.

    tan phi = 0.466308, sin alpha = 0.5 -> tan psi = 0.932615, cos psi = 0.731317;
    R_c = 0.5 * 4e4 * 0.03^2 (= 18) * (0.466308 + 0.1 * 0.906308 / 0.731317 = 0.590236)
          / (1 - 0.1 * 0.422618 / 0.731317 = 0.942211) = 11.2759 N;
    sqrt(E / (12 (1 - nu^2) g rho_w)) = sqrt(5e7 / 107123.4) = 21.6042 m^0.5;
    R_b = 27/64 * 4e4 * 0.3 * 0.03^1.5 / 21.6042 * (0.932615 + 0.1 * 0.906308 / (0.5 *
          0.731317) = 1.180467) * (1 + 1 / 0.731317 = 2.367396) = 3.40278 N;
    R_s = 100 * 9.81 * 0.03 * 0.3 * (0.1 * 0.4 / 0.5 = 0.08 + 0.1 * (1.05 - 0.214451
          - 0.129904 + 0.1 * 0.906308 * 0.731317 * sqrt(5.598978 + 3) = 0.194358)) = 1.50093 N;
    R = (R_c + R_b) * (1 + 1.4 * 0.5 / sqrt(0.2943) = 2.290336)
        + R_s * (1 + 9.4 * 0.5 / sqrt(14.715) = 2.225230) = 33.6190 + 3.3399 = 36.9590 N.
    """
    r = lindqvist_resistance(length=1.5, beam=0.3, draught=0.1, stem_angle=math.radians(25.0),
                             entrance_angle=math.radians(30.0), thickness=0.03,
                             bending_strength=4.0e4, youngs_modulus=5.0e7, speed=0.5,
                             friction=0.1, poisson_ratio=0.3, water_density=1000.0,
                             ice_density=900.0)
    assert math.tan(r["psi"]) == pytest.approx(0.932615, rel=1e-5)
    assert r["crushing"] == pytest.approx(11.2759, rel=1e-4)
    assert r["bending"] == pytest.approx(3.40278, rel=1e-4)
    assert r["submersion"] == pytest.approx(1.50093, rel=1e-4)
    assert r["breaking"] == pytest.approx(33.6190, rel=1e-4)
    assert r["total"] == pytest.approx(36.9590, rel=1e-4)


def test_steady_phase_of_a_harmonic_resistance():
    """R = 10 + 2 sin(2 pi 5 t) N after a contact at t = 0.2 s: over whole periods its mean
    is 10 N and its standard deviation 2 / sqrt(2) N (a sine's rms)."""
    t = np.linspace(0.0, 1.2, 120001)
    r = np.where(t >= 0.2, 10.0 + 2.0 * np.sin(2 * np.pi * 5.0 * t), 0.0)
    force = np.stack([-r, np.zeros_like(r), 0.5 * r], axis=1)   # the ice pushes the hull aft
    assert np.allclose(resistance_history(force), r)
    assert steady_start(t, r) == pytest.approx(0.2 + 0.6 * 1.0, abs=1e-4)
    f = steady_figures(t, r, start=0.4)                          # 0.4 .. 1.2 s: 4 periods
    assert f["mean"] == pytest.approx(10.0, rel=1e-6)
    assert f["std"] == pytest.approx(2.0 / math.sqrt(2.0), rel=1e-5)
    assert f["peak"] == pytest.approx(12.0, rel=1e-6)


def test_tiny_case_floats_at_its_draught():
    """The tiny case floats its sheet at the hydrostatic draught (bottom at -0.9 h,
    Archimedes with rho_i / rho_w = 0.9) and names its hull."""
    case = load_validation_case("icebreaker_tiny.toml")
    box = case.ice[0].shape
    h = box.max[2] - box.min[2]
    assert -box.min[2] == pytest.approx(case.ice[0].material.density / case.water.density * h)
    assert hull_names(case.text) == ["hull"]


def test_group_loads_are_the_steady_means_of_the_patch_histories():
    """Each hull group's load is the time-weighted mean of its patch history over the steady
    phase (here constant per group, so the mean is that constant), and its resistance is -F_x;
    groups that tile the hull (tests/motion/test_ship.py) add up to the hull's mean load."""
    from pdfem.post.resistance import group_resistance
    t = np.linspace(0.0, 1.0, 101)
    parts = {"bow": [-6.0, 1.0, 2.0], "shoulder": [-3.0, 0.5, 0.0], "stern": [1.0, 0.0, 0.0]}
    hist = {f"loads/hull.{g}": {"time": t, "force": np.where(t[:, None] >= 0.3, f, 0.0)}
            for g, f in parts.items()}
    hist["loads/hull"] = {"time": t, "force": sum(h["force"] for h in hist.values())}
    g = group_resistance({"histories": hist}, "hull", start=0.5)
    assert set(g) == set(parts)
    for name, f in parts.items():
        np.testing.assert_allclose(g[name]["force"], f, rtol=1e-12)
        assert g[name]["resistance"] == pytest.approx(-f[0], rel=1e-12)
    assert sum(v["resistance"] for v in g.values()) == pytest.approx(8.0, rel=1e-12)


def test_icebreaking_entries_measure_a_constructed_run(tmp_path):
    """The two ``pdfem validate`` entries of the tiny case on a constructed run: the steady
    mean of a resistance history against Lindqvist (1989) at zero speed (R_c + R_b + R_s of
    the hand computation above: 11.2759 + 3.40278 + 1.50093 = 16.1796 N), and the share of the
    channel's particles (|y| < B/2 = 0.15 m, x from the sheet's edge 0.76 m to the stem's end
    position less the entrance length) more than one thickness (0.03 m) below the sheet's
    bottom (-0.027 m)."""
    from pathlib import Path
    from pdfem.validation.case import Outcome
    from pdfem.validation.cases import icebreaking
    case = load_validation_case("icebreaker_tiny.toml")
    assert icebreaking.resistance_reference(case) == pytest.approx(16.1796, rel=1e-4)
    assert icebreaking.lindqvist_figures(case)["total"] == pytest.approx(36.9590, rel=1e-4)
    t = np.linspace(0.0, 1.2, 25)
    r = np.where(t > 0.13, 12.0, 0.0)
    force = np.stack([-r, np.zeros_like(r), r], axis=1)
    # the stem (x = 0.75 m on the hull) has moved 0.025 + 0.5 (1.2 - 0.1) = 0.575 m (the path):
    # at 1.325 m; the entrance is
    # 0.15 / tan 30 deg = 0.2598 m, so the channel reaches x = 1.065 m
    x0 = np.array([[0.8, 0.0, -0.01], [1.0, 0.1, -0.01], [1.06, -0.14, -0.02],
                   [1.07, 0.0, -0.01], [0.9, 0.16, -0.01], [0.7, 0.0, -0.01]])
    u = np.zeros((2, len(x0), 3))
    u[-1, :, 2] = [-0.2, -0.05, -0.01, -0.2, -0.2, -0.2]   # 1st and 2nd under, 3rd near the top
    data = {"time": t[[0, -1]], "histories": {"loads/hull": {"time": t, "force": force}},
            "ice": {"sheet": {"x0": x0, "u": u}}}
    outcome = Outcome(case, data, Path(tmp_path), 0.0)
    assert icebreaking.mean_resistance(outcome) == pytest.approx(12.0, rel=1e-12)
    assert icebreaking.submerged_fraction(outcome) == pytest.approx(2.0 / 3.0, rel=1e-12)
